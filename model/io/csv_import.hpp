// A user's own tracker export as a measurement campaign (docs/measurement-campaign.md): any separator
// (',', ';', tab) and decimal mark ('.' or ','), detected or given; metadata lines before the header
// skipped; the user's column names mapped to the campaign's (t, q1 .. qN, x, y, z, qm1 .. qmN, temp,
// payload); angles in degrees or radians, lengths in millimetres or metres.
#pragma once

#include <map>
#include <string>

#include "model/io/measurement_campaign.hpp"

namespace jointcomp {

struct CsvImportOptions {
  // Campaign column -> the export's header name ("q1" -> "A1"). Columns not mapped are looked up under
  // their own name, ignoring case (joint K also as joint_K or jointK). Without a time column the row index
  // is the time (1 s per row). x, y and z may be derived: "X_target+dX" is the sum of two columns (a
  // tracker's nominal position plus its deviation). A header column is mapped to one campaign column only,
  // a name found twice in the header is refused, and a mapped qK needs q1 .. qK-1 mapped or found.
  // A header column that looks like one more joint than those mapped is refused unless `joints` says
  // how many there are.
  std::map<std::string, std::string> columns;
  bool angles_in_radians = false;  // q and qm columns: degrees unless this says radians
  bool lengths_in_metres = false;  // x, y, z: millimetres unless this says metres
  char separator = 0;              // 0: detected from the header and the first row
  char decimal_mark = 0;           // 0: '.', or ',' when the separator is not ',' and the numbers use it
  std::string robot;               // the campaign's robot metadata ("" if not known)
  MeasurementFrame frame = MeasurementFrame::Base;
  int joints = 0;  // 0: as many as mapped or found, refused when the header seems to hold one more
  bool has_target = false;
  Eigen::Vector3d target_in_flange = Eigen::Vector3d::Zero();  // m, the campaign's `# target:`
};

// Throws MeasurementError naming the file, line and column (and, for a column not found, the header's
// names) for anything it cannot read; never drops a row.
MeasurementCampaign importCsvFile(const std::string& path, const CsvImportOptions& options);
MeasurementCampaign importCsv(const std::string& text, const std::string& source_name, const CsvImportOptions& options);

// "t=Time,q1=A1" -> {{"t", "Time"}, {"q1", "A1"}}; throws MeasurementError for an item without '='.
std::map<std::string, std::string> parseColumnMapping(const std::string& text);

}  // namespace jointcomp

// Importer of the IPA UR10 laser-tracker files (shared/data/ipa-ur10; Landgraf et al., IEEE CASE 2021,
// MIT licensed) into a measurement campaign: `;` separated with decimal commas, joints in rad, the
// T-Mac position in mm in the tracker's own frame. The result has frame = instrument, the target from
// the Trafo_TM_F_init file when given, joints in the campaign's units, and times from the timestamps
// (yyyymmddHHMMSS) where every row has a valid one, else from the row order (1 s per row). Rows whose
// timestamp goes back in time keep the previous time (the format needs a non-decreasing t); their count
// is kept in the metadata as time_held_rows.
#pragma once

#include <string>

#include "model/io/measurement_campaign.hpp"

namespace jointcomp {

// Throws MeasurementError naming the file, the line and the column for anything unreadable.
MeasurementCampaign importIpaUr10(const std::string& measurements_path, const std::string& trafo_path = "");
// The same from the measurement file's text (no target); `source_name` stands in for the file in messages.
MeasurementCampaign parseIpaUr10(const std::string& text, const std::string& source_name);

// The T-Mac point in the flange frame (m) from a Trafo_TM_F_init file: the 4x4 transform (mm) from
// flange to T-Mac, inverted. Throws MeasurementError for a malformed file.
Eigen::Vector3d ipaTargetInFlange(const std::string& trafo_path);

}  // namespace jointcomp

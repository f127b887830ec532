// Measurement campaigns (shared/formats/measurements.md, `jointcomp-measurements/1`): the robot was
// commanded through joint positions and an instrument measured where it actually was. Inside, SI units
// (rad, m, N, N m, kg); degrees and millimetres exist only in the file. A value that was not measured
// (an empty cell) is NaN inside.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "model/common/types.hpp"

namespace jointcomp {

enum class MeasurementFrame { Base, Instrument };

struct MeasurementCampaign {
  std::string source;                           // file name, for messages
  std::map<std::string, std::string> metadata;  // every `# key: value` line, known keys included
  std::string robot;
  MeasurementFrame frame = MeasurementFrame::Base;
  bool has_target = false;
  Eigen::Vector3d target_in_flange = Eigen::Vector3d::Zero();  // m
  // A known base frame (`# base_frame: x,y,z,rx,ry,rz`: mm and degrees, URDF roll-pitch-yaw): the robot
  // base's pose in the frame of an instrument-frame campaign, m = base_frame * p_base. Calibration starts
  // from it and fits it, or keeps it (--fix base); a campaign in the base frame has none.
  bool has_base_frame = false;
  Eigen::Isometry3d base_frame = Eigen::Isometry3d::Identity();
  double position_noise = 0.0;  // m, 1 sigma per axis; 0 when the file does not say
  double angle_noise = 0.0;     // rad, 1 sigma of qm; 0 when the file does not say

  int dof = 0;
  std::vector<double> time;          // s, non-decreasing
  std::vector<JointVector> command;  // rad
  bool has_position = false;
  std::vector<Eigen::Vector3d> position;  // m (NaN where not measured)
  bool has_measured_angles = false;
  std::vector<JointVector> measured_angles;  // rad (NaN where not measured)
  std::vector<double> temperature;           // degC (NaN where not measured or no column)
  std::vector<Vector6> wrench;               // N, N m at the target, base frame (zero without columns)
  std::vector<double> payload;               // kg (zero without the column)

  std::size_t size() const { return time.size(); }
  // Throws MeasurementError when the vectors disagree in length or break the format's rules.
  void validate() const;
};

// Throws MeasurementError naming the file, the line and the column for anything the format forbids:
// a missing format line or required column, a non-numeric or non-finite cell, a decreasing t, a row
// with the wrong number of cells. It never drops a row.
MeasurementCampaign readCampaignFile(const std::string& path);
MeasurementCampaign parseCampaign(const std::string& text, const std::string& source_name);

// The campaign with only the rows `keep` says true for (given the row's index), in their order, with every
// column and the campaign's metadata: a subset to fit or hold out.
MeasurementCampaign campaignRows(const MeasurementCampaign& campaign, const std::function<bool(std::size_t)>& keep);

// A base frame from x,y,z (mm), rx,ry,rz (deg, URDF roll-pitch-yaw: R = Rz(rz) Ry(ry) Rx(rx)), as the
// `# base_frame:` line and `--base-frame` give it, and the line's text of a base frame (17 digits).
Eigen::Isometry3d baseFrameFromValues(const std::vector<double>& mm_and_deg);
std::string baseFrameText(const Eigen::Isometry3d& base_frame);

// Writes the campaign in the format (degrees and millimetres), whole or not at all.
std::string campaignToText(const MeasurementCampaign& campaign);
void writeCampaignFile(const MeasurementCampaign& campaign, const std::string& path);

}  // namespace jointcomp

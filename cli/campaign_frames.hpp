// What calibrate and discover share about where the campaigns were measured: the target on the flange
// (--target, the campaigns' `# target:`, the parameter file's "tool") and the robot base's pose in the
// instrument's frame (--base-frame, the campaigns' `# base_frame:`),
// the --fix groups ("target", "frame", "base"), and how far the fitted geometry may go (--geometry-limits).
#pragma once

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "cli/robot_setup.hpp"
#include "model/identify/geometric_calibration.hpp"
#include "model/io/measurement_campaign.hpp"
#include "model/io/urdf_writer.hpp"

namespace jointcomp::cli {

// --geometry-limits OFFSET_DEG,SHIFT_MM,TURN_DEG: what a joint's zero, its axis's place and its axis's turn
// may be corrected by (GeometryLimits; each above 0); the defaults when not given.
inline GeometryLimits geometryLimitsFrom(const Options& options) {
  GeometryLimits limits;
  if (!options.has("geometry-limits")) return limits;
  const std::vector<double> values =
      numberList(options.get("geometry-limits", ""), "geometry-limits", {0.0, 1e6, true});
  if (values.size() != 3)
    throw UsageError("--geometry-limits takes OFFSET_DEG,SHIFT_MM,TURN_DEG (three numbers above 0)");
  constexpr double kDegree = 3.14159265358979323846 / 180.0;  // rad
  limits.offset = values[0] * kDegree;
  limits.placement_shift = values[1] * 1e-3;
  limits.placement_turn = values[2] * kDegree;
  return limits;
}

// --fix takes parameter names, and "target", "frame" and "base" (the same six as "frame": the base's pose
// in the instrument's frame) for their groups.
inline std::vector<std::string> expandedFixNames(const std::vector<std::string>& names) {
  std::vector<std::string> out;
  for (const std::string& name : names) {
    if (name == "target") {
      for (const char* axis : {"x", "y", "z"}) out.push_back(std::string("target.") + axis + "_m");
    } else if (name == "frame" || name == "base") {
      for (const char* p : {"tx_m", "ty_m", "tz_m", "rx_rad", "ry_rad", "rz_rad"})
        out.push_back(std::string("frame.") + p);
    } else {
      out.push_back(name);
    }
  }
  return out;
}

// The target on the flange every campaign is calibrated with: --target, else the campaigns' own `# target:`,
// else the "tool" of the parameter file (a calibrated robot's, on the URDF it was measured from). Returns
// where it came from ("" when from the campaigns or nowhere).
inline std::string applyTarget(const Options& options, const RobotSetup& setup,
                               const std::vector<MeasurementCampaign*>& campaigns) {
  Eigen::Vector3d target;
  std::string from;
  if (options.has("target")) {
    const std::vector<double> mm = numberList(options.get("target", ""), "target", {-1e4, 1e4});
    if (mm.size() != 3) throw UsageError("--target takes x,y,z in mm");
    target = Eigen::Vector3d(mm[0], mm[1], mm[2]) * 1e-3;
    from = "--target";
  } else if (setup.parameters.tool && !campaigns.front()->has_target &&
             setup.parameters.tool->flange_link == setup.robot->tip_link) {
    target = setup.parameters.tool->in_flange;
    from = setup.params + " (tool)";
  } else {
    return "";
  }
  for (MeasurementCampaign* campaign : campaigns) {
    campaign->has_target = true;
    campaign->target_in_flange = target;
  }
  return from;
}

// The base's pose in the instrument's frame: --base-frame x,y,z,rx,ry,rz (mm, deg, URDF roll-pitch-yaw),
// else the campaigns' own `# base_frame:`.
// Given, every campaign is one in the instrument's frame that starts there; a campaign that says
// `frame: base` is refused. Returns where it came from ("" when from the campaigns or nowhere).
inline std::string applyBaseFrame(const Options& options, const std::vector<MeasurementCampaign*>& campaigns) {
  Eigen::Isometry3d frame;
  std::string from;
  if (options.has("base-frame")) {
    const std::vector<double> values = numberList(options.get("base-frame", ""), "base-frame", {-1e5, 1e5});
    if (values.size() != 6) throw UsageError("--base-frame takes x,y,z,rx,ry,rz in mm and deg");
    for (int k = 3; k < 6; ++k) {
      if (std::abs(values[static_cast<std::size_t>(k)]) > 360.0)
        throw UsageError("--base-frame: an angle beyond 360 deg");
    }
    frame = baseFrameFromValues(values);
    from = "--base-frame";
  } else {
    return "";
  }
  for (MeasurementCampaign* campaign : campaigns) {
    if (campaign->frame == MeasurementFrame::Base) {
      throw UsageError(from + ": campaign '" + campaign->source +
                       "' says 'frame: base' (its positions are in the base frame already); a base frame places "
                       "the base in an instrument's frame");
    }
    campaign->has_base_frame = true;
    campaign->base_frame = frame;
  }
  return from;
}

// Both of the above on the fitted and held-out campaigns, each source said on the console.
inline void applyCampaignFrames(const Options& options, const RobotSetup& setup,
                                std::vector<MeasurementCampaign>& fitted,
                                const std::vector<MeasurementCampaign*>& held) {
  std::vector<MeasurementCampaign*> all;  // the first fitted campaign first
  for (MeasurementCampaign& campaign : fitted) all.push_back(&campaign);
  all.insert(all.end(), held.begin(), held.end());
  const std::string target_from = applyTarget(options, setup, all);
  if (!target_from.empty()) std::printf("  target on the flange from %s\n", target_from.c_str());
  const std::string base_from = applyBaseFrame(options, all);
  if (!base_from.empty()) std::printf("  base frame from %s\n", base_from.c_str());
}

}  // namespace jointcomp::cli

// The noise of the instruments of simulated and measured campaigns, and how a campaign file states it.
//
// Laser tracker (Leica AT9xx class): MPE about +-(15 um + 6 um/m) (reference/rx170.md). jointcomp takes
// the MPE as about 2 sigma, so 1 sigma per axis is (15 um + 6 um/m * distance from the tracker) / 2 =
// 7.5 um + 3 um/m. Electronic level (Wyler/Leica class inclinometers): 1 sigma = 0.001 deg = 3.6 arcsec
// per reading, our choice for a good precision level. A joint angle measured as the difference of two
// levels has sqrt(2) times that.
//
// A campaign keeps the format's one-number summary (noise_mm: the RMS of the per-row tracker sigma;
// noise_deg: the sigma of the qm columns) and, as extra metadata keys the reader keeps, the model itself:
//   tracker_sigma_constant_mm, tracker_sigma_per_m_mm, tracker_position_mm (x,y,z), level_sigma_deg.
#pragma once

#include <optional>
#include <vector>

#include "model/io/measurement_campaign.hpp"

namespace jointcomp {

struct TrackerNoiseModel {
  double constant_m = 7.5e-6;                        // 15 um / 2
  double per_metre = 3.0e-6;                         // 6 um/m / 2
  Eigen::Vector3d tracker_position{3.0, -2.0, 0.5};  // m, base frame
  // 1-sigma noise per axis of a point measured at `point` (base frame).
  double sigma(const Eigen::Vector3d& point) const {
    return constant_m + per_metre * (point - tracker_position).norm();
  }
};

struct LevelNoiseModel {
  double sigma_rad = 0.001 * 3.14159265358979323846 / 180.0;  // per reading
};

// Writes the tracker model into the campaign's metadata (the position_noise summary is set separately).
void writeTrackerNoise(const TrackerNoiseModel& model, MeasurementCampaign& campaign);
void writeLevelNoise(const LevelNoiseModel& model, MeasurementCampaign& campaign);
// The tracker model of a campaign's metadata when all three keys are there. Throws MeasurementError
// naming the key when one is malformed or only some are there.
std::optional<TrackerNoiseModel> trackerNoiseOf(const MeasurementCampaign& campaign);

// Per-row 1-sigma noise of x, y, z: the tracker model when the campaign states one, else noise_mm for
// every row, else NaN (unknown: the identifications then weigh rows alike and estimate the scale).
std::vector<double> positionSigmaPerRow(const MeasurementCampaign& campaign);

}  // namespace jointcomp

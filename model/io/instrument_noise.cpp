#include "model/io/instrument_noise.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>

#include "model/common/errors.hpp"

namespace jointcomp {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

std::string formatNumber(double value) {
  char buffer[40];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t") - first + 1);
}

std::vector<double> metadataNumbers(const MeasurementCampaign& campaign, const std::string& key, std::size_t count) {
  const std::string& text = campaign.metadata.at(key);
  std::vector<double> values;
  std::stringstream list(text);
  std::string item;
  while (std::getline(list, item, ',')) {
    item = trim(item);
    double value = 0.0;
    const auto result = std::from_chars(item.data(), item.data() + item.size(), value);
    if (item.empty() || result.ec != std::errc() || result.ptr != item.data() + item.size() || !std::isfinite(value)) {
      throw MeasurementError(campaign.source + ": metadata '" + key + "': '" + item + "' is not a finite number");
    }
    values.push_back(value);
  }
  if (values.size() != count) {
    throw MeasurementError(campaign.source + ": metadata '" + key + "' must hold " + std::to_string(count) +
                           (count == 1 ? " number" : " numbers separated by ','"));
  }
  return values;
}

}  // namespace

void writeTrackerNoise(const TrackerNoiseModel& model, MeasurementCampaign& campaign) {
  campaign.metadata["tracker_sigma_constant_mm"] = formatNumber(model.constant_m * 1e3);
  campaign.metadata["tracker_sigma_per_m_mm"] = formatNumber(model.per_metre * 1e3);
  campaign.metadata["tracker_position_mm"] = formatNumber(model.tracker_position.x() * 1e3) + "," +
                                             formatNumber(model.tracker_position.y() * 1e3) + "," +
                                             formatNumber(model.tracker_position.z() * 1e3);
}

void writeLevelNoise(const LevelNoiseModel& model, MeasurementCampaign& campaign) {
  campaign.metadata["level_sigma_deg"] = formatNumber(model.sigma_rad / kDegree);
}

std::optional<TrackerNoiseModel> trackerNoiseOf(const MeasurementCampaign& campaign) {
  const char* keys[3] = {"tracker_sigma_constant_mm", "tracker_sigma_per_m_mm", "tracker_position_mm"};
  int present = 0;
  for (const char* key : keys) present += campaign.metadata.count(key) > 0 ? 1 : 0;
  if (present == 0) return std::nullopt;
  if (present != 3) {
    throw MeasurementError(
        campaign.source +
        ": metadata tracker_sigma_constant_mm, tracker_sigma_per_m_mm and tracker_position_mm go together");
  }
  TrackerNoiseModel model;
  model.constant_m = metadataNumbers(campaign, keys[0], 1)[0] * 1e-3;
  model.per_metre = metadataNumbers(campaign, keys[1], 1)[0] * 1e-3;
  const std::vector<double> position = metadataNumbers(campaign, keys[2], 3);
  model.tracker_position = Eigen::Vector3d(position[0], position[1], position[2]) * 1e-3;
  if (model.constant_m < 0.0 || model.per_metre < 0.0 || model.constant_m + model.per_metre <= 0.0) {
    throw MeasurementError(campaign.source + ": metadata tracker_sigma_*: the noise must be positive");
  }
  return model;
}

std::vector<double> positionSigmaPerRow(const MeasurementCampaign& campaign) {
  std::vector<double> sigma(campaign.size(), std::numeric_limits<double>::quiet_NaN());
  if (!campaign.has_position) return sigma;
  const std::optional<TrackerNoiseModel> tracker = trackerNoiseOf(campaign);
  for (std::size_t k = 0; k < campaign.size(); ++k) {
    if (tracker && campaign.position[k].allFinite()) {
      sigma[k] = tracker->sigma(campaign.position[k]);
    } else if (campaign.position_noise > 0.0) {
      sigma[k] = campaign.position_noise;
    }
  }
  return sigma;
}

}  // namespace jointcomp

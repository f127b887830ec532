#include "model/identify/residual_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <tuple>

namespace jointcomp {

namespace {

double rms(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size()));
}

std::string summaryOf(const Robot& robot, const UnexplainedResidual& u, double fitted_rms) {
  char text[256];
  std::string s;
  if (u.over_floor > 0.0) {
    std::snprintf(text, sizeof(text), "what is left: fitted RMS %.4f mm, %.1f times the noise floor. It lies in ",
                  fitted_rms * 1e3, u.over_floor);
  } else {
    std::snprintf(text, sizeof(text), "what is left: fitted RMS %.4f mm (noise floor not known). It lies in ",
                  fitted_rms * 1e3);
  }
  s += text;
  // The joints that carry most of it: by their share at the target (a wrist joint's milliradian moves the
  // target less than a shoulder's), until three quarters of the sum of squares.
  double total = 0.0;
  for (double r : u.joint_rms_m) total += r * r;
  double covered = 0.0;
  for (std::size_t k = 0; k < u.joints.size(); ++k) {
    const int j = u.joints[k];
    std::snprintf(text, sizeof(text), "%s%s (%.4f mrad, %.4f mm RMS)", k == 0 ? "" : ", ", robot.joints[j].name.c_str(),
                  u.joint_rms_rad[j] * 1e3, u.joint_rms_m[j] * 1e3);
    s += text;
    covered += u.joint_rms_m[j] * u.joint_rms_m[j];
    if (covered >= 0.75 * total) break;
  }
  s += "; repeating orders: ";
  int named = 0;
  for (const ResidualOrder& o : u.orders) {
    if (!o.stands_out || named == 4) continue;
    std::snprintf(text, sizeof(text), "%s%s %s order %d (%.4f mrad)", named == 0 ? "" : ", ",
                  robot.joints[o.joint].name.c_str(), o.angle.c_str(), o.order, o.amplitude_rad * 1e3);
    s += text;
    ++named;
  }
  if (named == 0) s += "none stands out of its joint's spectrum";
  s += "; over time: ";
  if (u.block_rms.empty()) return s + "not known.";
  const auto [low, high] = std::minmax_element(u.block_rms.begin(), u.block_rms.end());
  std::snprintf(text, sizeof(text), "%.4f to %.4f mm RMS per block of consecutive rows (%zu blocks), %s.", *low * 1e3,
                *high * 1e3, u.block_rms.size(),
                *high > 1.5 * *low ? "uneven: it changes with time or with where each block went" : "even");
  return s + text;
}

}  // namespace

UnexplainedResidual analyseUnexplained(const Robot& robot, const ResidualRows& rows, double fitted_rms,
                                       double noise_floor) {
  UnexplainedResidual u;
  const int n = robot.dof();
  u.over_floor = noise_floor > 0.0 ? fitted_rms / noise_floor : 0.0;
  u.floor_known = noise_floor > 0.0;
  u.above_floor = u.floor_known && fitted_rms > kUnexplainedFactor * noise_floor;
  for (int j = 0; j < n && j < static_cast<int>(rows.joint_residual.size()); ++j) {
    const std::vector<double>& dq = rows.joint_residual[static_cast<std::size_t>(j)];
    u.joint_rms_rad.push_back(rms(dq));
    std::vector<double> at_target;
    for (std::size_t i = 0; i < dq.size(); ++i) {
      const bool lever_known = static_cast<int>(rows.joint_lever.size()) > j && i < rows.joint_lever[j].size();
      at_target.push_back(dq[i] * (lever_known ? rows.joint_lever[static_cast<std::size_t>(j)][i] : 1.0));
    }
    u.joint_rms_m.push_back(rms(at_target));
  }
  u.joints.resize(u.joint_rms_rad.size());
  std::iota(u.joints.begin(), u.joints.end(), 0);
  std::stable_sort(u.joints.begin(), u.joints.end(), [&](int a, int b) { return u.joint_rms_m[a] > u.joint_rms_m[b]; });
  for (int j = 0; j < static_cast<int>(u.joint_rms_rad.size()); ++j) {
    std::vector<double> output, motor;
    for (std::size_t i = 0; i < rows.output_angle.size(); ++i) {
      output.push_back(rows.output_angle[i][j]);
      if (i < rows.motor_angle.size()) motor.push_back(rows.motor_angle[i][j]);
    }
    const std::vector<double>& residual = rows.joint_residual[static_cast<std::size_t>(j)];
    for (const auto& [name, angle, max_order] : {std::make_tuple("output", &output, kMaxScannedOutputOrder),
                                                 std::make_tuple("motor", &motor, kMaxScannedMotorOrder)}) {
      const OrderPeak peak = strongestOrder(residual, *angle, 1, max_order);
      if (peak.order == 0) continue;
      u.orders.push_back({j, name, peak.order, peak.amplitude, peak.stands_out});
    }
  }
  std::stable_sort(u.orders.begin(), u.orders.end(), [](const ResidualOrder& a, const ResidualOrder& b) {
    if (a.stands_out != b.stands_out) return a.stands_out;
    return a.amplitude_rad > b.amplitude_rad;
  });
  // Blocks of consecutive rows.
  std::vector<double> sum, count;
  for (std::size_t i = 0; i < rows.residual_norm.size() && i < rows.block.size(); ++i) {
    const std::size_t b = static_cast<std::size_t>(std::max(0, rows.block[i]));
    if (b >= sum.size()) {
      sum.resize(b + 1, 0.0);
      count.resize(b + 1, 0.0);
    }
    sum[b] += rows.residual_norm[i] * rows.residual_norm[i];
    count[b] += 1.0;
  }
  for (std::size_t b = 0; b < sum.size(); ++b) u.block_rms.push_back(count[b] > 0 ? std::sqrt(sum[b] / count[b]) : 0.0);
  u.summary = summaryOf(robot, u, fitted_rms);
  return u;
}

}  // namespace jointcomp

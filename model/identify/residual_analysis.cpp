#include "model/identify/residual_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <tuple>

#include "model/common/errors.hpp"
#include "model/common/median.hpp"

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
  if (u.block_rms.empty()) {
    s += "not known.";
  } else {
    const auto [low, high] = std::minmax_element(u.block_rms.begin(), u.block_rms.end());
    std::snprintf(text, sizeof(text), "%.4f to %.4f mm RMS per block of consecutive rows (%zu blocks), %s.", *low * 1e3,
                  *high * 1e3, u.block_rms.size(),
                  *high > 1.5 * *low ? "uneven: it changes with time or with where each block went" : "even");
    s += text;
  }
  return u.pose.computed ? s + " " + describePosePredictability(u.pose) : s;
}

// The mean distance (rad) to the k nearest candidates of `i` and the mean of their residuals; false when fewer
// than k candidates pass `admit`.
// Candidates are every `step`-th row, so that the work stays bounded on very long campaigns.
template <class Admit>
bool nearestMean(const std::vector<JointVector>& q, const std::vector<Eigen::Vector3d>& residual, std::size_t i, int k,
                 std::size_t step, Admit admit, std::vector<std::pair<double, std::size_t>>& best, double& distance,
                 Eigen::Vector3d& mean) {
  best.clear();
  for (std::size_t j = 0; j < q.size(); j += step) {
    if (j == i || !admit(j)) continue;
    const double d2 = (q[j] - q[i]).squaredNorm();
    if (static_cast<int>(best.size()) == k && d2 >= best.back().first) continue;
    if (static_cast<int>(best.size()) < k)
      best.emplace_back(d2, j);
    else
      best.back() = {d2, j};
    // Keep the k best sorted: one insertion step.
    for (std::size_t m = best.size() - 1; m > 0 && best[m].first < best[m - 1].first; --m)
      std::swap(best[m], best[m - 1]);
  }
  if (static_cast<int>(best.size()) < k) return false;
  distance = 0.0;
  mean.setZero();
  for (const auto& [d2, j] : best) {
    distance += std::sqrt(d2);
    mean += residual[j];
  }
  distance /= k;
  mean /= k;
  return true;
}

}  // namespace

std::string describePosePredictability(const PosePredictability& p) {
  if (!p.computed) return "As a function of the pose: not known (too few rows, or none measured far enough apart).";
  char text[256];
  std::string s;
  std::snprintf(text, sizeof(text),
                "As a function of the pose: the mean of the %d nearest poses measured at least %.0f s apart (%.3f rad "
                "away) leaves %.4f of %.4f mm, ",
                p.neighbours, p.min_gap_s, p.median_distance_other_times, p.left_other_times_rms * 1e3,
                p.residual_rms * 1e3);
  s += text;
  if (p.median_distance_other_times > kPoseSparseDistance) {
    s += "but the campaign's poses lie too far apart to tell whether it is a function of the pose";
  } else {
    std::snprintf(text, sizeof(text), "so at least %.0f %% of its variance is a function of the pose at this sampling",
                  100.0 * p.smooth_share);
    s += text;
  }
  std::snprintf(text, sizeof(text), "; the nearest at any time (%.3f rad away) leave %.4f mm",
                p.median_distance_any_time, p.left_any_time_rms * 1e3);
  s += text;
  if (p.left_any_time_rms < 0.75 * p.left_other_times_rms)
    s += ": rows close in time agree, rows far apart do not, so the rest changes between visits or over poses closer "
         "than the campaign samples";
  return s + ".";
}

PosePredictability posePredictability(const std::vector<JointVector>& q, const std::vector<Eigen::Vector3d>& residual,
                                      const std::vector<double>& time, int neighbours, double min_gap_s,
                                      int max_scored_rows) {
  if (residual.size() != q.size() || time.size() != q.size())
    throw InvalidArgument("posePredictability: " + std::to_string(q.size()) + " joint vectors, " +
                          std::to_string(residual.size()) + " residuals and " + std::to_string(time.size()) +
                          " times; they must be as many");
  if (neighbours < 1 || !(min_gap_s >= 0.0) || max_scored_rows < 1)
    throw InvalidArgument("posePredictability: neighbours and max_scored_rows must be at least 1 and min_gap_s >= 0");
  for (std::size_t i = 0; i < q.size(); ++i) {
    if (!q[i].allFinite() || !residual[i].allFinite() || !std::isfinite(time[i]) ||
        (i > 0 && q[i].size() != q[0].size()))
      throw InvalidArgument("posePredictability: row " + std::to_string(i) +
                            " has a non-finite value or a joint vector of another size");
  }
  PosePredictability p;
  p.neighbours = neighbours;
  p.min_gap_s = min_gap_s;
  const std::size_t n = q.size();
  if (n < static_cast<std::size_t>(neighbours) + 2) return p;
  const std::size_t stride =
      (n + static_cast<std::size_t>(max_scored_rows) - 1) / static_cast<std::size_t>(max_scored_rows);
  // At most kPoseMaxCandidateRows candidate neighbours: a stride on very long campaigns (the estimate then
  // sees the pose more coarsely; it stays a lower bound).
  const std::size_t step = (n + kPoseMaxCandidateRows - 1) / kPoseMaxCandidateRows;
  std::vector<std::pair<double, std::size_t>> best;
  best.reserve(static_cast<std::size_t>(neighbours));
  double sum_rr = 0.0, sum_other = 0.0, sum_any = 0.0;
  std::vector<double> distance_other, distance_any;
  for (std::size_t i = 0; i < n; i += stride) {
    double d_other = 0.0, d_any = 0.0;
    Eigen::Vector3d mean_other = Eigen::Vector3d::Zero(), mean_any = Eigen::Vector3d::Zero();
    const bool other = nearestMean(
        q, residual, i, neighbours, step, [&](std::size_t j) { return std::abs(time[j] - time[i]) >= min_gap_s; }, best,
        d_other, mean_other);
    if (!other) continue;
    nearestMean(
        q, residual, i, neighbours, step, [](std::size_t) { return true; }, best, d_any, mean_any);
    sum_rr += residual[i].squaredNorm();
    sum_other += (residual[i] - mean_other).squaredNorm();
    sum_any += (residual[i] - mean_any).squaredNorm();
    distance_other.push_back(d_other);
    distance_any.push_back(d_any);
  }
  p.scored_rows = static_cast<int>(distance_other.size());
  if (p.scored_rows < neighbours + 1 || sum_rr <= 0.0) return p;
  const double scored = static_cast<double>(p.scored_rows);
  p.computed = true;
  p.residual_rms = std::sqrt(sum_rr / scored);
  p.left_other_times_rms = std::sqrt(sum_other / scored);
  p.left_any_time_rms = std::sqrt(sum_any / scored);
  p.median_distance_other_times = median(distance_other);
  p.median_distance_any_time = median(distance_any);
  const double noise_only = (1.0 + 1.0 / neighbours) * sum_rr;
  p.smooth_share = std::clamp(1.0 - sum_other / noise_only, 0.0, 1.0);
  return p;
}

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
    if (static_cast<int>(rows.joint_share.size()) > j) {
      double sum = 0.0;
      for (double share : rows.joint_share[static_cast<std::size_t>(j)]) sum += share;
      const double count = static_cast<double>(rows.joint_share[static_cast<std::size_t>(j)].size());
      u.joint_rms_m.push_back(count > 0 ? std::sqrt(sum / count) : 0.0);
      continue;
    }
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
    bool motor_differs = false;  // a directly driven joint's motor is its output: scanned once, as the output
    for (std::size_t i = 0; i < motor.size() && !motor_differs; ++i)
      motor_differs = std::abs(motor[i] - output[i]) > 1e-12;
    for (const auto& [name, angle, max_order] : {std::make_tuple("output", &output, kMaxScannedOutputOrder),
                                                 std::make_tuple("motor", &motor, kMaxScannedMotorOrder)}) {
      if (angle == &motor && !motor_differs) continue;
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
  if (!rows.residual.empty()) u.pose = posePredictability(rows.output_angle, rows.residual, rows.time);
  u.summary = summaryOf(robot, u, fitted_rms);
  return u;
}

}  // namespace jointcomp

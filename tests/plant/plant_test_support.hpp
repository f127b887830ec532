// What the plant tests share: the RX170 with its shipped parameters, and independent re-derivations of
// the transmission error and of the static load, written out from the effects' definitions.
#pragma once

#include <cmath>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/effects/joint_error_model.hpp"
#include "model/effects/spring_balancer.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::plant_testing {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;
inline const std::string kUrdf = JOINTCOMP_DATA_DIR "/robots/rx170.urdf";
inline const std::string kParameters = JOINTCOMP_DATA_DIR "/params/rx170.json";

inline std::shared_ptr<const Robot> rx170() {
  static const auto robot = std::make_shared<const Robot>(loadRobotFromUrdfFile(kUrdf));
  return robot;
}

inline JointVector joints(std::initializer_list<double> degrees) {
  JointVector q(static_cast<int>(degrees.size()));
  int i = 0;
  for (double d : degrees) q[i++] = d * kDegree;
  return q;
}

// A slow swing of every drive from rest through a cosine about `centre()` (amplitudes 2 to 4 degrees, 0.1 to
// 0.2 Hz: slow enough that CVODE's steps are a few ms, as on the paper's spiral; swings of 5 to 15 degrees at
// 0.2 to 0.45 Hz held CVODE near 0.4 ms): its value q and rate v at t, as a co-simulation master feeds them.
inline const JointVector& swingCentre() {
  static const JointVector q = joints({20.0, 45.0, 70.0, 30.0, 50.0, 10.0});
  return q;
}
inline void swingAt(double t, JointVector& q, JointVector& v) {
  const JointVector amplitude = joints({3.0, 2.0, 2.5, 4.0, 3.0, 2.0});
  const double hertz[6] = {0.1, 0.12, 0.14, 0.16, 0.18, 0.2};
  q = swingCentre();
  v = JointVector::Zero(6);
  for (int j = 0; j < 6; ++j) {
    const double w = 2.0 * kPi * hertz[j];
    q[j] += amplitude[j] * (1.0 - std::cos(w * t));
    v[j] = amplitude[j] * w * std::sin(w * t);
  }
}

// Transmission error of the gears at motor positions p (joint units), written out from the harmonics:
// the angle of stage s's input shaft is (G p)_j divided by the ratios of the stages before it.
inline JointVector transmissionErrorAt(const JointErrorModel& model, const JointVector& p) {
  JointVector e = JointVector::Zero(p.size());
  const int index = model.findEffect(TransmissionErrorEffect::kType);
  if (index < 0) return e;
  const auto& effect = dynamic_cast<const TransmissionErrorEffect&>(model.effect(index));
  const JointVector motor = model.gears().motorFromJoint() * p;
  for (const Harmonic& h : effect.harmonics()) {
    double ratio_before = 1.0;
    for (int s = 1; s < h.stage; ++s) ratio_before *= model.gears().stageRatios(h.joint)[s - 1];
    e[h.joint] += h.amplitude_rad * std::sin(h.cycles_per_revolution * motor[h.joint] / ratio_before + h.phase_rad);
  }
  return e;
}

// Torque the joints carry at rest at q: gravity plus the spring balancer(s).
inline JointVector staticLoad(const JointErrorModel& model, const JointVector& q) {
  RobotWorkspace ws(model.robot());
  JointVector load;
  gravityTorques(model.robot(), ws, q, load);
  for (int i = 0; i < model.effectCount(); ++i) {
    if (const auto* spring = dynamic_cast<const SpringBalancerEffect*>(&model.effect(i))) {
      load[spring->joint()] += spring->torque(q[spring->joint()]);
    }
  }
  return load;
}

// Runs `call`, expecting an exception of type E whose message contains every one of `words`.
template <class E, class F>
void expectThrowMentioning(F call, const std::vector<std::string>& words, const std::string& what) {
  try {
    call();
    ADD_FAILURE() << what << ": no exception";
  } catch (const E& e) {
    const std::string message = e.what();
    for (const std::string& word : words) {
      EXPECT_NE(message.find(word), std::string::npos) << what << ": '" << word << "' not in: " << message;
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << ": wrong exception type: " << e.what();
  }
}

}  // namespace jointcomp::plant_testing

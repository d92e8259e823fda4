// Neural3Points physics mode with the default model-based controller: retargeting, standing
// upright, delay bookkeeping, tracker correction, fall detection and recovery, bad input.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>

#include "n3p_physics/common.hpp"

using namespace sparsebody;
using n3p_physics_test::finite_output;
using n3p_physics_test::Physics;
using n3p_physics_test::user_frame;

TEST_CASE("n3p physics retarget: q -> pose -> q is exact; the standing pose stands on the floor") {
  Physics p(n3p_physics_test::weights());
  p.set_calibration({});  // synthetic users: trackers at the joints, body convention
  const auto& m = p.model();
  const auto& r = p.retarget();
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  std::uniform_real_distribution<double> u(-2.5, 2.5);
  pose::BodyPose pose;
  pose.resize(p.skeleton().size());
  for (int trial = 0; trial < 20; ++trial) {
    Physics::VecQ q = m.neutral_configuration(), back = q;
    for (int i = 0; i < m.nb; ++i) {
      const auto& b = m.bodies[i];
      if (b.joint == dynamics::JointType::Revolute) {
        q(b.q_index) = float(u(rng));
      } else {
        const int k = b.joint == dynamics::JointType::Free ? b.q_index + 3 : b.q_index;
        Eigen::Quaterniond Q(std::abs(n(rng)), n(rng), n(rng), n(rng));
        Q.normalize();
        q(k) = float(Q.w()); q(k + 1) = float(Q.x()); q(k + 2) = float(Q.y()); q(k + 3) = float(Q.z());
        if (b.joint == dynamics::JointType::Free)
          for (int a = 0; a < 3; ++a) q(b.q_index + a) = float(u(rng));
      }
    }
    r.to_pose(m, q, pose);
    r.to_q(m, pose, back);
    CHECK((q - back).cwiseAbs().maxCoeff() < 2e-5);
  }
  // The avatar's reference pose (straight, soles on the floor) is the skeleton standing straight
  // at meta.standing_hips_height: q -> pose puts the root there, and the hips upright.
  const Physics::VecQ q = m.neutral_configuration();
  r.to_pose(m, q, pose);
  pose::WorldPose wp;
  wp.resize(p.skeleton().size());
  pose::forward_kinematics(p.skeleton(), pose, wp);
  const int ul = p.skeleton().find("UpperLeg_L"), ur = p.skeleton().find("UpperLeg_R");
  CHECK(0.5 * (wp.position[ul].y() + wp.position[ur].y()) == doctest::Approx(double(m.bodies[0].pos.y()) - r.lift()).epsilon(1e-6));
  CHECK(std::abs(pose.root_position.y() - p.meta().standing_hips_height) < 0.08);
  // Straight legs: the skeleton's knee and ankle lie below the hip joint.
  const int kl = p.skeleton().find("LowerLeg_L"), fl = p.skeleton().find("Foot_L");
  CHECK(std::hypot(wp.position[fl].x() - wp.position[ul].x(), wp.position[fl].z() - wp.position[ul].z()) < 0.05);
  CHECK(wp.position[kl].y() < wp.position[ul].y() - 0.3);
}

TEST_CASE("n3p physics: the model-based controller keeps a standing user upright for 10 s") {
  Physics p(n3p_physics_test::weights());
  p.set_calibration({});  // synthetic users: trackers at the joints, body convention
  const double max_force = p.config().controller.max_force, max_torque = p.config().controller.max_torque;
  int frames = 0, airborne = 0;
  for (int t = 0; t < 300; ++t) {
    p.push(user_frame(t, 0.0));
    if (!p.has_output()) continue;
    ++frames;
    const auto& d = p.simulator().data();
    const auto& ref = p.reference();
    REQUIRE(finite_output(p));
    CHECK(d.p[0].y() > ref(1) - 0.1);   // root height stays near the predicted one
    CHECK(d.p[0].y() < ref(1) + 0.05);
    CHECK(d.R[0](1, 1) > std::cos(0.3));  // tilt below 0.3 rad
    CHECK(p.residual().force <= max_force * (1 + 1e-6));  // float rounding of the bounded norm
    CHECK(p.residual().torque <= max_torque * (1 + 1e-6));
    CHECK(p.penetration() < 0.01);
    airborne += !(p.contact(0) || p.contact(1));
  }
  // Standing: on its feet. The predictor's start (from its default state to the user's pose, the
  // reference root rising 1 cm in 0.2 s) lifts both feet for one frame with the acceleration
  // feed-forward; none after it.
  std::printf("[stand] frames without a foot on the ground: %d of %d; residual force mean %.1f N\n", airborne, frames,
              p.residual_stats().force_mean());
  CHECK(airborne <= 1);
  CHECK(frames >= 295);
  CHECK(p.falls() == 0);
  CHECK(p.sim_failures() == 0);
  CHECK(p.residual_stats().steps == 4LL * frames);
  // The help needed to stand is well below the bound on average.
  CHECK(p.residual_stats().force_mean() < 0.6 * max_force);
}

TEST_CASE("n3p physics: the output is the input frame 0.1 s back") {
  Physics p(n3p_physics_test::weights());
  p.set_calibration({});  // synthetic users: trackers at the joints, body convention
  for (int t = 0; t < 60; ++t) {
    const auto f = user_frame(t, 0.0);
    p.push(f);
    if (t >= 10) {
      REQUIRE(p.has_output());
      CHECK(p.output_time() == doctest::Approx(f.time - Physics::delay_seconds()).epsilon(1e-6));
      CHECK(p.output_frame() == t - Physics::kDelayFrames);
    }
  }
}

TEST_CASE("n3p physics: tracker correction turns F into arm torques that move the hand along F") {
  Physics p(n3p_physics_test::weights());
  p.set_calibration({});  // synthetic users: trackers at the joints, body convention
  const auto& m = p.model();
  control::TrackerCorrection<float, 24, 72> tc(m);
  dynamics::Data<float, 24, 72> d(m);
  Physics::VecQ q = m.neutral_configuration();
  Physics::VecV v = Physics::VecV::Zero(m.nv), tau = Physics::VecV::Zero(m.nv);
  dynamics::forward_kinematics(m, d, q, &v);
  const int h = tc.hand_body(0);
  const dynamics::Vec3<float> target[2] = {d.p[h] + dynamics::Vec3<float>(0, -0.1f, 0.05f), d.p[tc.hand_body(1)]};
  const bool present[2] = {true, false};
  tc.apply(m, d, target, present, tau);
  CHECK(tc.force(0) == doctest::Approx(1000 * std::sqrt(0.0125)).epsilon(1e-4));  // kp |e|, at rest
  CHECK(tc.force(1) == 0);
  // Only the left arm chain is actuated, and J tau points along F (J J^T F . F > 0).
  Eigen::Matrix<float, 6, Eigen::Dynamic, 0, 6, 72> J(6, m.nv);
  const dynamics::Vec3<float> origin = dynamics::Vec3<float>::Zero();
  dynamics::body_jacobian(m, d, h, origin, J);
  const dynamics::Vec3<float> hand_motion = J.bottomRows<3>() * tau;
  CHECK(hand_motion.dot(target[0] - d.p[h]) > 0);
  for (int i = 0; i < m.nb; ++i) {
    const bool arm = m.names[i] == "Shoulder_L" || m.names[i] == "UpperArm_L" || m.names[i] == "LowerArm_L" || m.names[i] == "Hand_L";
    if (!arm)
      for (int k = 0; k < m.nv_of(i); ++k) CHECK(tau(m.bodies[i].v_index + k) == 0);
  }
}

TEST_CASE("n3p physics fall detector: height, tilt, divergence") {
  control::FallDetector f;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY(), ref(0, 0.9, 0);
  CHECK(f.update(ref, up, ref, up) == control::FallReason::None);
  CHECK(f.update(Eigen::Vector3d(0, 0.3, 0), up, ref, up) == control::FallReason::Height);
  CHECK(f.update(Eigen::Vector3d(0, 0.5, 0), up, ref, up) == control::FallReason::Height);  // 0.4 m drop
  CHECK(f.update(ref, Eigen::Vector3d(1, 0.2, 0), ref, up) == control::FallReason::Tilt);
  CHECK(f.update(ref, Eigen::Vector3d(1, 0.2, 0), ref, Eigen::Vector3d(1, 0.2, 0)) == control::FallReason::None);
  control::FallReason r = control::FallReason::None;
  int k = 0;
  for (; k < 30 && r == control::FallReason::None; ++k) r = f.update(Eigen::Vector3d(0.6, 0.9, 0), up, ref, up);
  CHECK(r == control::FallReason::Diverged);
  CHECK(k == f.config().error_frames);
  CHECK(f.falls() == 4);
  CHECK(f.update(Eigen::Vector3d(0, std::numeric_limits<double>::quiet_NaN(), 0), up, ref, up) == control::FallReason::Height);
}

TEST_CASE("n3p physics: a fall resets the character to the predicted pose and the simulation resumes") {
  avatar::N3PPhysicsConfig c;
  c.fall.min_height = 5.0;  // every frame counts as a fall
  Physics p(n3p_physics_test::weights(), c);
  p.set_calibration({});  // synthetic users: trackers at the joints, body convention
  long long frames = 0;
  for (int t = 0; t < 60; ++t) {
    p.push(user_frame(t, 1.0));
    if (!p.has_output()) continue;
    ++frames;
    // Reset: the state is the reference of the frame being tracked, lifted out of the floor
    // (ground_resets): only the root height differs, by what puts the lowest point on the floor.
    Physics::VecQ dq = p.simulator().q() - p.reference();
    CHECK(dq(1) >= 0);
    CHECK(dq(1) <= p.config().controller.max_ground_lift + 1e-6);
    dq(1) = 0;
    CHECK(dq.cwiseAbs().maxCoeff() < 1e-5);
    CHECK(p.penetration() < 1e-5);
    REQUIRE(finite_output(p));
  }
  CHECK(p.falls() == frames);
  // Back to normal limits: the character resumes from there and stays up.
  avatar::N3PPhysicsConfig c2;
  c2.controller.max_force = 0;  // no help at all: it must fall while walking, and be put back
  c2.controller.max_torque = 0;
  Physics q(n3p_physics_test::weights(), c2);
  q.set_calibration({});  // synthetic users: trackers at the joints, body convention
  for (int t = 0; t < 300; ++t) {
    q.push(user_frame(t, 1.2));
    if (!q.has_output()) continue;
    REQUIRE(finite_output(q));
    CHECK(q.simulator().data().p[0].y() > c2.fall.min_height - 0.1);  // never left lying on the floor
  }
  CHECK(q.falls() > 0);
  CHECK(q.residual_stats().force_max == 0);
}

TEST_CASE("n3p physics: NaN, lost trackers and jumps give finite output and defined recovery") {
  Physics p(n3p_physics_test::weights());
  p.set_calibration({});  // synthetic users: trackers at the joints, body convention
  const double nan = std::numeric_limits<double>::quiet_NaN();
  long long restarts = 0;
  for (int t = 0; t < 420; ++t) {
    trackers::TrackerFrame f = user_frame(t, 0.6);
    if (t >= 60 && t < 65) f.pose[0].position.x = static_cast<float>(nan);  // NaN headset
    if (t >= 90 && t < 100) f.pose[1].orientation.w = static_cast<float>(nan);  // NaN controller
    if (t >= 120 && t < 180) f.valid[2] = false;   // right controller lost for 2 s
    if (t >= 200 && t < 230) f.valid[0] = false;   // headset lost for 1 s
    if (t >= 300) {  // the tracking origin jumps by 5 m
      f.pose[0].position.x += 5.0f;
      f.pose[1].position.x += 5.0f;
      f.pose[2].position.x += 5.0f;
    }
    if (t == 299) restarts = p.restarts();
    p.push(f);
    if (!p.has_output()) continue;
    REQUIRE(finite_output(p));
    CHECK(p.simulator().q().allFinite());
    if (t == 340) CHECK(std::abs(p.pose().root_position.x() - p.direct().pose().root_position.x()) < 0.5);
  }
  CHECK(p.restarts() > restarts);  // the jump restarted the physics on the new reference
  CHECK(p.sim_failures() == 0);
}

TEST_CASE("n3p physics: ground_lift is how far the lowest contact point is below the floor") {
  Physics p(n3p_physics_test::weights());
  p.set_calibration({});  // synthetic users: trackers at the joints, body convention
  const auto& m = p.model();
  control::ModelBasedController<float, 24, 72> ctl(m);
  Physics::VecQ q = m.neutral_configuration();
  dynamics::Data<float, 24, 72> d(m);
  auto lowest = [&](const Physics::VecQ& x) {
    dynamics::forward_kinematics(m, d, x, static_cast<const Physics::VecV*>(nullptr), true);
    float lo = 1e9f;
    for (int k = 0; k < m.num_points; ++k)
      lo = std::min(lo, dynamics::point_position(d, m.points[k].body, m.points[k].pos).y() - m.points[k].radius);
    return lo;
  };
  q(1) += 0.3f - lowest(q);  // lowest point 0.3 m up: nothing to lift
  CHECK(ctl.ground_lift(m, q) == 0);
  q(1) -= 0.34f;  // 4 cm into the floor
  CHECK(ctl.ground_lift(m, q) == doctest::Approx(0.04).epsilon(1e-4));
  q(1) -= 1.0f;  // bounded
  CHECK(ctl.ground_lift(m, q) == doctest::Approx(ctl.config().max_ground_lift));
}

// The learned-policy path of the physics mode against PyTorch: the policy input s
// (control/n3p_policy_input.hpp vs weights_tool/n3p_physics/policy_input.py) on random character
// states and predicted states, and the control policy pi (N3PPolicyNet, seeded random weights
// exported by weights_tool.n3p_physics; RL policies are not shipped) on that s. The reference is
// generated at test time with ${SPARSEBODY_PYTHON} into the build directory.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "n3p_physics/common.hpp"
#include "support/alloc_counter.hpp"

#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/control/n3p_policy_input.hpp"
#include "sparsebody/networks/policy_nets.hpp"
#include "sparsebody/nn/network.hpp"

using namespace sparsebody;
namespace np = control::n3p_policy;

TEST_CASE("n3p physics policy input and policy: C++ equals PyTorch (float <= 1e-4)") {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0, 1);
  std::uniform_real_distribution<double> u(-3.1, 3.1);
  const int lower[9] = {0, 13, 14, 15, 16, 17, 18, 19, 20};
  const int upper[12] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  const features::HeadingFrame href{n(rng), n(rng), u(rng)};
  Eigen::Vector3d p[np::kJoints], v[np::kJoints];
  Eigen::Matrix3d R[np::kJoints];
  nlohmann::json in;
  in["h_ref"] = {href.px, href.pz, href.theta};
  in["lower"] = lower;
  in["upper"] = upper;
  for (int j = 0; j < np::kJoints; ++j) {
    p[j] = Eigen::Vector3d(n(rng), 1 + 0.3 * n(rng), n(rng));
    v[j] = Eigen::Vector3d(n(rng), n(rng), n(rng));
    R[j] = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
    in["p"].push_back({p[j].x(), p[j].y(), p[j].z()});
    in["v"].push_back({v[j].x(), v[j].y(), v[j].z()});
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) in["R"].push_back(R[j](a, b));
  }
  features::HeadingFrame hk[3];
  std::vector<double> glo[3], gup[3];
  for (int k = 0; k < 3; ++k) {
    hk[k] = {href.px + 0.3 * n(rng), href.pz + 0.3 * n(rng), u(rng)};
    for (int i = 0; i < features::n3p::kGlo; ++i) glo[k].push_back(n(rng));
    for (int i = 0; i < features::n3p::kGup; ++i) gup[k].push_back(n(rng));
    in["future"].push_back({{"h", {hk[k].px, hk[k].pz, hk[k].theta}}, {"g_lo", glo[k]}, {"g_up", gup[k]}});
  }
  const std::string dir = std::string(SPARSEBODY_BINARY_DIR) + "/n3p_physics_reference";
  std::system(("mkdir -p " + dir).c_str());
  { std::ofstream(dir + "/input.json") << in.dump(); }
  const std::string cmd = std::string("cd ") + SPARSEBODY_SOURCE_DIR + " && " + SPARSEBODY_PYTHON +
                          " -m weights_tool.n3p_physics reference " + dir + "/input.json " + dir;
  REQUIRE(std::system(cmd.c_str()) == 0);
  std::ifstream f(dir + "/n3p_policy_reference.json");
  REQUIRE(f.good());
  const auto ref = nlohmann::json::parse(f);

  // s in float, as the controller builds it.
  std::array<float, np::kPolicyIn> s{};
  np::character_block(href, p, v, R, s.data());
  for (int k = 0; k < 3; ++k)
    np::predicted_block(href, hk[k], glo[k].data(), gup[k].data(), lower, upper, s.data() + np::kBlock * (1 + k));
  REQUIRE(ref["s"].size() == np::kPolicyIn);
  double worst_s = 0;
  for (int i = 0; i < np::kPolicyIn; ++i) worst_s = std::max(worst_s, std::abs(s[i] - ref["s"][i].get<double>()));
  CHECK(worst_s <= 1e-4);

  using Net = networks::N3PPolicyNet<float, np::kPolicyIn, np::kPolicyOut>;
  const auto w = nn::NetworkWeights<Net>::load(dir + "/n3p_policy_random.json", networks::kN3PPolicyKind);
  nn::Network<Net> pi(w);
  const float* y = pi.step(s.data());
  double worst_u = 0, scale = 0;
  for (int i = 0; i < np::kPolicyOut; ++i) {
    worst_u = std::max(worst_u, std::abs(y[i] - ref["u"][i].get<double>()));
    scale = std::max(scale, std::abs(ref["u"][i].get<double>()));
  }
  MESSAGE("policy input max |diff| " << worst_s << ", policy output max |diff| " << worst_u << " (max |u| " << scale << ")");
  CHECK(worst_u <= 1e-4 * std::max(1.0, scale));
  CHECK(scale > 1e-3);  // a non-trivial output
}

// The physics pipeline driven by the combined control predictor and a (random, untrained) policy:
// it must run, keep its output finite, count its control steps, recover from the falls an
// untrained policy causes, and allocate nothing per frame.
TEST_CASE("n3p physics policy path: runs, recovers from falls, no allocation per frame") {
  using Physics = avatar::N3PPhysicsDefault;
  const std::string dir = std::string(SPARSEBODY_BINARY_DIR) + "/n3p_physics_reference";
  std::ifstream probe(dir + "/n3p_policy_random.json");
  REQUIRE_MESSAGE(probe.good(), "run the parity test case first (it writes the random policy)");
  const auto w = Physics::load(SPARSEBODY_N3P_WEIGHTS);
  Physics p(w, Physics::ControlPredictor::load_policy(dir + "/n3p_policy_random.json"));
  p.set_calibration({});  // synthetic users: trackers at the joints, body convention
  CHECK(p.controller_kind() == avatar::ControllerKind::Policy);
  auto frame = [](int t) {
    trackers::TrackerFrame f;
    f.time = t / 30.0;
    const double a = 0.3 * t / 30.0;
    const Eigen::Vector3d c(1.5 * std::sin(a), 0, 1.5 * std::cos(a));
    const Eigen::Quaterniond yaw(Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitY()));
    const Eigen::Vector3d pos[3] = {c + Eigen::Vector3d(0, 1.378, 0), c + yaw * Eigen::Vector3d(0.2, 0.8, 0), c + yaw * Eigen::Vector3d(-0.2, 0.8, 0)};
    for (int k = 0; k < 3; ++k) {
      f.pose[k].position = trackers::to_xr(pos[k]);
      f.pose[k].orientation = trackers::to_xr(yaw);
      f.valid[k] = true;
    }
    return f;
  };
  for (int t = 0; t < 10; ++t) p.push(frame(t));
  long long allocations = 0;
  {
    sparsebody_test::AllocationCounter counter;
    for (int t = 10; t < 160; ++t) p.push(frame(t));
    allocations = counter.count();
  }
  CHECK(allocations == 0);
  CHECK(p.has_output());
  CHECK(p.policy_steps() >= 45);
  CHECK(p.residual_stats().force_max == 0);  // no non-physical help on the policy path
  CHECK(n3p_physics_test::finite_output(p));
  CHECK(p.simulator().data().p[0].y() > 0.0);
  const auto& s = p.control_predictor()->policy_input();
  bool s_finite = true;
  for (float x : s) s_finite &= std::isfinite(x);
  CHECK(s_finite);
}

// §6 "apply IK to the trackers": in the rollout states the policy sees (2, 5, 8: frames t, t+3,
// t+6), each hand joint is on its controller (received at t, forecast by Eq. (18) after it) unless
// out of the arm's reach, where the arm is straight towards it; without the IK it is not.
TEST_CASE("n3p control predictor: the rollout's hands are put on the trackers by IK") {
  using Physics = avatar::N3PPhysicsDefault;
  const std::string dir = std::string(SPARSEBODY_BINARY_DIR) + "/n3p_physics_reference";
  std::ifstream probe(dir + "/n3p_policy_random.json");
  REQUIRE_MESSAGE(probe.good(), "run the parity test case first (it writes the random policy)");
  const auto w = Physics::load(SPARSEBODY_N3P_WEIGHTS);
  const auto policy = Physics::ControlPredictor::load_policy(dir + "/n3p_policy_random.json");
  Physics with(w, policy), without(w, policy);
  with.set_calibration({});  // synthetic users: trackers at the joints, body convention
  without.set_calibration({});
  without.control_predictor()->tracker_ik = false;
  auto frame = [](int t) {  // walking forward, hands swinging in front of the hips
    trackers::TrackerFrame f;
    f.time = t / 30.0;
    const double x = 1.0 * t / 30.0, swing = 0.15 * std::sin(2 * M_PI * t / 30.0);
    const Eigen::Vector3d pos[3] = {Eigen::Vector3d(0, 1.378, x), Eigen::Vector3d(0.22, 0.9, x + swing + 0.1),
                                    Eigen::Vector3d(-0.22, 0.9, x - swing + 0.1)};
    for (int k = 0; k < 3; ++k) {
      f.pose[k].position = trackers::to_xr(pos[k]);
      f.pose[k].orientation = trackers::to_xr(Eigen::Quaterniond::Identity());
      f.valid[k] = true;
    }
    return f;
  };
  std::vector<std::array<Eigen::Vector3d, 2>> hands;  // calibrated controller positions per frame
  double err_with = 0, err_without = 0, worst_reached = 0;
  int checked = 0, reached = 0;
  long long steps = 0;
  for (int t = 0; t < 120; ++t) {
    with.push(frame(t));
    without.push(frame(t));
    hands.push_back({with.direct().trackers()[1].p, with.direct().trackers()[2].p});
    if (with.policy_steps() == steps) continue;  // no control step this frame
    steps = with.policy_steps();
    REQUIRE(without.policy_steps() == steps);
    const auto* a = with.control_predictor();
    const auto* b = without.control_predictor();
    const int n = static_cast<int>(hands.size()) - 1;
    for (int side = 0; side < 2; ++side) {
      const Eigen::Vector3d delta = 0.5 * (hands[n][side] - hands[n - 2][side]);  // Eq. (18) average offset
      for (int k : {2, 5, 8}) {
        const Eigen::Vector3d target = hands[n][side] + double(k - 2) * delta;
        const int sh = a->arm_joint(side, 0), el = a->arm_joint(side, 1), hd = a->arm_joint(side, 2);
        const Eigen::Vector3d s = a->rollout_upper_position(k, sh), e = a->rollout_upper_position(k, el),
                              h = a->rollout_upper_position(k, hd);
        const double e_ik = (h - target).norm();
        err_with += e_ik;
        err_without += (b->rollout_upper_position(k, hd) - target).norm();
        ++checked;
        const double reach = (e - s).norm() + (h - e).norm();
        if ((target - s).norm() < reach - 1e-3) {  // reachable: on the target
          ++reached;
          worst_reached = std::max(worst_reached, e_ik);
        } else {  // out of reach: straight arm pointing at it
          CHECK((h - s).norm() == doctest::Approx(reach).epsilon(1e-3));
          CHECK((h - s).normalized().dot((target - s).normalized()) > 0.999);
        }
      }
    }
  }
  std::printf("[n3p-ik] %d rollout hands: mean error to the controller %.4f m with IK, %.4f m without; %d reachable, worst %.2e m\n",
              checked, err_with / std::max(1, checked), err_without / std::max(1, checked), reached, worst_reached);
  CHECK(checked >= 6 * 30);
  CHECK(reached > checked / 2);
  CHECK(worst_reached < 1e-4);  // float storage of g
  CHECK(err_without / checked > 0.02);  // the network alone does not put them there
}

// The learned-policy path of the physics mode against PyTorch: the policy input s
// (control/n3p_policy_input.hpp vs weights_tool/n3p_physics/policy_input.py) on random character
// states and predicted states, and the control policy pi (N3PPolicyNet, seeded random weights
// exported by weights_tool.n3p_physics; RL policies are not shipped) on that s. The reference is
// generated at test time with ${SPARSEBODY_PYTHON} into the build directory.
#include <doctest/doctest.h>

#include <cstdlib>
#include <fstream>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

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

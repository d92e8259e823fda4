// The default weights (examples/weights/n3p_*.json, paper sizes 64/128/128): C++ == PyTorch over a
// CMU clip (3-point, then HMD-only), and the direct-mode pipeline on them: finite output, hands on
// the controllers whenever they are within reach.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>

#include "n3p/common.hpp"

using namespace sparsebody;

namespace {
using Paper = avatar::N3PDirect;
std::string prefix() { return std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights/n3p"; }
}  // namespace

TEST_CASE("n3p default weights: C++ equals PyTorch over a clip at the paper's sizes") {
  const auto g = n3p_test::read_json(n3p_test::golden_dir() + "/n3p_default.golden.json");
  const auto w = Paper::load(prefix());
  CHECK(w.lo->info().meta.value("credit", std::string()).find("Bandai Namco") != std::string::npos);
  Paper::Predictor p(w);
  pose::WorldPose world;
  world.resize(p.skeleton().size());
  double worst = 0;
  const int F = g["frames"];
  for (int t = 0; t < F; ++t) {
    std::array<bool, 3> present{};
    for (int k = 0; k < 3; ++k) present[k] = g["present"][t][k].get<int>() != 0;
    REQUIRE(p.step(n3p_test::golden_trackers(g, t), present));
    auto cmp = [&](double a, double b) { worst = std::max(worst, std::abs(a - b) / std::max(1.0, std::abs(b))); };
    cmp(p.heading().px, g["h"][t][0]);
    cmp(p.heading().pz, g["h"][t][1]);
    cmp(features::wrap_angle(p.heading().theta - g["h"][t][2].get<double>()) + 0.0, 0.0);
    for (int i = 0; i < features::n3p::kZ; ++i) cmp(p.z_tilde()[i], g["z"][t][i]);
    for (int i = 0; i < features::n3p::kO; ++i) cmp(p.o_star()[i], g["o_star"][t][i]);
    pose::forward_kinematics(p.skeleton(), p.pose(), world);
    for (int j = 0; j < p.skeleton().size(); ++j)
      for (int i = 0; i < 3; ++i) cmp(world.position[j][i], g["positions"][t][3 * j + i]);
  }
  MESSAGE("worst relative difference over " << F << " frames: " << worst);
  CHECK(worst <= 1e-4);
}

TEST_CASE("n3p default weights: direct mode puts reachable hands on the controllers, never NaN") {
  const auto g = n3p_test::read_json(n3p_test::golden_dir() + "/n3p_default.golden.json");
  Paper p(Paper::load(prefix()));
  // synthetic trackers at the joints in the body convention: the identity calibration
  p.set_calibration({});
  const int hand[2] = {p.skeleton().find("Hand_L"), p.skeleton().find("Hand_R")};
  int reachable = 0, on = 0;
  for (int t = 0; t < g["frames"].get<int>(); ++t) {
    const auto f = n3p_test::golden_frame(g, t);
    p.push(f);
    REQUIRE(p.has_output());
    for (int j = 0; j < p.skeleton().size(); ++j) REQUIRE(p.world().position[j].allFinite());
    for (int s = 0; s < 2; ++s) {
      if (!f.valid[1 + s]) continue;
      const Eigen::Vector3d target = trackers::to_eigen(f.pose[1 + s].position);
      const double reach = p.skeleton().offsets[hand[s]].norm() + p.skeleton().offsets[hand[s] - 1].norm();
      if ((target - p.world().position[hand[s] - 2]).norm() < reach - 1e-3) {
        ++reachable;
        on += (p.world().position[hand[s]] - target).norm() < 1e-5;
      }
    }
  }
  MESSAGE("controllers within reach of the predicted shoulders: " << reachable);
  CHECK(on == reachable);
}

// C++ N3PPredictor == the PyTorch reference (weights_tool/n3p/model.py rollout) over a whole clip,
// autoregressively (each frame feeds on the previous frame's own outputs), including HMD-only and
// one-controller stretches where o* stands in for the missing controllers. Float tolerance 1e-4.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>

#include "n3p/common.hpp"
#include "sparsebody/pose/body_pose.hpp"

using namespace sparsebody;
namespace n3p = features::n3p;

namespace {
double worst = 0;
void near(double a, double b, const char* what, int t, int i, double tol = 1e-4) {
  const double e = std::abs(a - b) / std::max(1.0, std::abs(b));
  worst = std::max(worst, e);
  if (!(e <= tol)) FAIL_CHECK(what << " frame " << t << " [" << i << "]: C++ " << a << " vs PyTorch " << b);
}
}  // namespace

TEST_CASE("n3p predictor: C++ equals the PyTorch reference over a whole clip (3-point, HMD-only, one controller)") {
  const auto g = n3p_test::read_json(n3p_test::golden_dir() + "/n3p_small.golden.json");
  const auto w = n3p_test::SmallPredictor::load(n3p_test::small_prefix());
  n3p_test::SmallPredictor p(w);
  pose::WorldPose world;
  world.resize(p.skeleton().size());
  const int F = g["frames"], every = g["state_every"];
  REQUIRE(F >= 180);
  int hmd_frames = 0, one_frames = 0;
  for (int t = 0; t < F; ++t) {
    const auto o = n3p_test::golden_trackers(g, t);
    std::array<bool, 3> present{};
    for (int k = 0; k < 3; ++k) present[k] = g["present"][t][k].get<int>() != 0;
    hmd_frames += (!present[1] && !present[2]);
    one_frames += (present[1] != present[2]);
    REQUIRE(p.step(o, present));
    for (int k = 0; k < 3; ++k) CHECK(p.substituted(k) == !present[k]);
    const auto& h = g["h"][t];
    near(p.heading().px, h[0], "h.px", t, 0);
    near(p.heading().pz, h[1], "h.pz", t, 1);
    near(features::wrap_angle(p.heading().theta - h[2].get<double>()), 0.0, "h.theta", t, 2);
    for (int i = 0; i < n3p::kZ; ++i) near(p.z_tilde()[i], g["z"][t][i], "z~", t, i);
    for (int i = 0; i < n3p::kO; ++i) near(p.o_star()[i], g["o_star"][t][i], "o*", t, i);
    if (t % every == 0) {
      for (int i = 0; i < n3p::kGlo; ++i) near(p.g_lo()[i], g["g_lo"][t / every][i], "g_lo", t, i);
      for (int i = 0; i < n3p::kGup; ++i) near(p.g_up()[i], g["g_up"][t / every][i], "g_up", t, i);
    }
    pose::forward_kinematics(p.skeleton(), p.pose(), world);
    for (int j = 0; j < p.skeleton().size(); ++j)
      for (int i = 0; i < 3; ++i) near(world.position[j][i], g["positions"][t][3 * j + i], "FK position", t, 3 * j + i);
  }
  CHECK(hmd_frames >= 30);
  CHECK(one_frames >= 30);
  MESSAGE("worst relative difference over " << F << " frames: " << worst);
}

TEST_CASE("n3p predictor: a different step (perturbed tracker) is detected by the parity comparison") {
  // The comparison above can fail: moving the head 30 cm at one frame changes the outputs
  // well beyond the tolerance.
  const auto g = n3p_test::read_json(n3p_test::golden_dir() + "/n3p_small.golden.json");
  n3p_test::SmallPredictor p(n3p_test::SmallPredictor::load(n3p_test::small_prefix()));
  double diff = 0;
  for (int t = 0; t < 20; ++t) {
    auto o = n3p_test::golden_trackers(g, t);
    if (t == 10) o[0].p.x() += 0.3;
    REQUIRE(p.step(o, {true, true, true}));
    if (t >= 10)
      for (int i = 0; i < n3p::kO; ++i) diff = std::max(diff, std::abs(p.o_star()[i] - g["o_star"][t][i].get<double>()));
  }
  CHECK(diff > 1e-4);
}

TEST_CASE("n3p weights: meta is checked") {
  const auto w = n3p_test::SmallPredictor::load(n3p_test::small_prefix() + "_lower.json");  // any one file names the set
  CHECK(w.sig->info().kind == "n3p_signal");
  CHECK(w.up->info().kind == "n3p_upper");
  CHECK_THROWS_AS(n3p_test::SmallPredictor::load(n3p_test::golden_dir() + "/missing"), LoadError);
  // wrong hidden size for the file
  CHECK_THROWS_AS((predict::N3PPredictor<float, 64, 128, 128>::load(n3p_test::small_prefix())), LoadError);
}

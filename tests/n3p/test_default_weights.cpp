// The default weights (examples/weights/n3p_*.json, paper sizes 64/128/128): C++ == PyTorch over a
// CMU clip (3-point, then HMD-only), and the direct-mode pipeline on them: finite output, hands on
// the controllers whenever they are within reach.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "n3p/common.hpp"
#include "support/standing_stream.hpp"

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

// Standing still (issue 12: feet <= 1 cm/s): a synthetic session that walks, stands 4 s, walks.
// Over the stand's last 3 s (the stillness detector has engaged) the toes' mean horizontal speed
// stays under 1 cm/s, and the head joint sits on the calibrated headset (head reach). Without the
// stillness hold the same stand creeps faster (what the hold is for).
TEST_CASE("n3p default weights: feet stay put and the head on the headset while the user stands still") {
  using sparsebody_test::Phase;
  const auto w = Paper::load(prefix());
  const auto s = sparsebody_test::session({{Phase::Walk, 2.0, 1.62}, {Phase::Stand, 4.0, 1.62}, {Phase::Walk, 1.0, 1.62}}, 72.0, 0.3, false);
  auto run = [&](bool hold, double* head_err) {
    avatar::N3PConfig c;
    c.hold_feet_when_still = hold;
    Paper p(w, c);
    const int toe[2] = {p.joint_map()[pose::Role::ToeL], p.joint_map()[pose::Role::ToeR]};
    const int head = p.joint_map()[pose::Role::Head];
    Eigen::Vector3d prev[2];
    bool have = false;
    double sum = 0, herr = 0;
    int n = 0;
    for (const auto& f : s) {
      if (p.push(f) == 0 || !p.has_output()) continue;
      Eigen::Vector3d now[2];
      for (int k = 0; k < 2; ++k) now[k] = p.world().position[toe[k]] * p.user_scale();
      if (f.time > 3.0 && f.time < 6.0 && have) {
        for (int k = 0; k < 2; ++k) sum += std::hypot(now[k].x() - prev[k].x(), now[k].z() - prev[k].z()) * 30.0 / 2;
        herr += (p.world().position[head] - p.trackers()[0].p).norm() * p.user_scale();
        ++n;
      }
      for (int k = 0; k < 2; ++k) prev[k] = now[k];
      have = true;
    }
    REQUIRE(n > 60);
    *head_err = herr / n;
    return sum / n;
  };
  double head_hold = 0, head_free = 0;
  const double held = run(true, &head_hold), free = run(false, &head_free);
  MESSAGE("toe speed standing still: " << 100 * held << " cm/s held, " << 100 * free << " cm/s without the hold; head joint "
                                       << 100 * head_hold << " cm from the calibrated headset");
  CHECK(held < 0.01);
  // The toes are what is pinned (N3PConfig::Pin::Toe), so with or without the hold they do not
  // move here. With the paper's ankle pin the toes turned about the pinned ankles: 0.15 cm/s
  // without the hold, 0.13 with it (the hold keeps the planted feet's orientation).
  CHECK(held <= free + 1e-6);
  CHECK(head_hold < 0.01);
}

TEST_CASE("n3p default weights: head height: the body walks up onto a platform and kneels with the headset") {
  using sparsebody_test::Phase;
  const auto w = Paper::load(prefix());
  // 2 s standing (eye 1.62 m), 2 s walking, 3 s standing. Up: every tracker rises 0.4 m over the
  // walk (a ramp onto a platform). Down: every tracker sinks 0.6 m over the last stand's first
  // 0.5 s (kneeling). Calibrated explicitly on the first frame, so the automatic search does not
  // resize the body to the new eye height. Measured over the last 2 s.
  const auto s = sparsebody_test::session({{Phase::Stand, 2.0, 1.62}, {Phase::Walk, 2.0, 1.62}, {Phase::Stand, 3.0, 1.62}}, 72.0,
                                          0.3, false);
  auto run = [&](bool follow, bool up, double* toe_y) {
    avatar::N3PConfig c;
    c.head_height = follow;
    Paper p(w, c);
    REQUIRE(p.calibrate(s.front()));
    const int toe[2] = {p.joint_map()[pose::Role::ToeL], p.joint_map()[pose::Role::ToeR]};
    const int head = p.joint_map()[pose::Role::Head];
    double err = 0;
    int n = 0;
    *toe_y = std::numeric_limits<double>::infinity();
    for (auto f : s) {
      const double d = up ? 0.4 * std::clamp((f.time - 2.0) / 2.0, 0.0, 1.0) : -0.6 * std::clamp((f.time - 4.0) / 0.5, 0.0, 1.0);
      for (auto& pose : f.pose) pose.position.y += static_cast<float>(d);
      if (p.push(f) == 0 || !p.has_output() || f.time < 5.0) continue;
      err += std::abs(p.world().position[head].y() - p.trackers()[0].p.y()) * p.user_scale();
      for (int k = 0; k < 2; ++k) *toe_y = std::min(*toe_y, p.world().position[toe[k]].y() * p.user_scale());
      ++n;
    }
    REQUIRE(n > 40);
    return err / n;
  };
  double toe_on = 0, toe_off = 0;
  const double up_on = run(true, true, &toe_on), up_off = run(false, true, &toe_off);
  MESSAGE("0.4 m up: head " << 100 * up_on << " cm from the headset (" << 100 * up_off << " cm without head_height), lowest toe "
                             << 100 * toe_on << " cm (" << 100 * toe_off << ")");
  CHECK(up_off > 0.25);
  // the dead band (2 cm, standard scale) and a little: the walk ends with feet pinned where its last
  // steps were made, below the platform, and while the user stands they rise with the head
  // (N3PConfig::platform_height; without it the head stayed 4-11 cm below, by the weights)
  CHECK(up_on < 0.03);
  CHECK(toe_on > 0.35);  // the feet came up with the body onto the 0.4 m platform
  const double down_on = run(true, false, &toe_on), down_off = run(false, false, &toe_off);
  MESSAGE("0.6 m down: head " << 100 * down_on << " cm from the headset (" << 100 * down_off << " cm without head_height), lowest toe "
                               << 100 * toe_on << " cm (" << 100 * toe_off << ")");
  CHECK(down_off > 0.1);
  CHECK(down_on < 0.03);
  CHECK(toe_on > -0.02);  // the legs bend: the feet are not pushed into the floor
}

TEST_CASE("n3p default weights: head height: a jump takes the feet off the floor at once, and they land") {
  using sparsebody_test::Phase;
  const auto w = Paper::load(prefix());
  const auto s = sparsebody_test::session({{Phase::Stand, 4.0, 1.62}}, 72.0, 0.3, false);
  // a 25 cm jump at 2 s: every tracker up and down in 0.45 s
  auto run = [&](double jump_speed, double* worst_in_air, double* toe_after) {
    avatar::N3PConfig c;
    c.head_height_jump_speed = jump_speed;
    Paper p(w, c);
    REQUIRE(p.calibrate(s.front()));
    const int toe[2] = {p.joint_map()[pose::Role::ToeL], p.joint_map()[pose::Role::ToeR]};
    const int head = p.joint_map()[pose::Role::Head];
    *worst_in_air = *toe_after = 0;
    for (auto f : s) {
      const double t = f.time - 2.0, T = 0.45;
      const double d = t > 0 && t < T ? 0.25 * std::sin(M_PI * t / T) : 0.0;
      for (auto& pose : f.pose) pose.position.y += static_cast<float>(d);
      if (p.push(f) == 0 || !p.has_output()) continue;
      const double err = std::abs(p.trackers()[0].p.y() - p.world().position[head].y()) * p.user_scale();
      if (t > 0.07 && t < T) *worst_in_air = std::max(*worst_in_air, err);  // from the third frame of the jump
      if (t > T + 0.3)
        for (int k = 0; k < 2; ++k) *toe_after = std::max(*toe_after, p.world().position[toe[k]].y() * p.user_scale());
    }
  };
  double air = 0, after = 0, air_slow = 0, after_slow = 0;
  run(avatar::N3PConfig{}.head_height_jump_speed, &air, &after);  // the default: 1.2 m/s
  run(std::numeric_limits<double>::infinity(), &air_slow, &after_slow);
  MESSAGE("25 cm jump: head at most " << 100 * air << " cm from the headset in the air (" << 100 * air_slow
                                      << " cm lifting only beyond the release height); highest toe after landing " << 100 * after << " cm");
  CHECK(air < 0.03);        // the band (2 cm, standard scale) and a little
  CHECK(air_slow > 0.1);    // the pins held the body down until the release height
  CHECK(after < 0.06);      // back on the floor (a standing toe joint is ~4 cm up)
}

TEST_CASE("n3p default weights: controllers held beyond the standard arm's reach lengthen the arms; the hands reach them") {
  using sparsebody_test::Phase;
  const auto w = Paper::load(prefix());
  auto run = [&](bool fit, double* gap, double* arm) {
    avatar::N3PConfig cfg;
    cfg.arm_reach.enabled = fit;
    Paper p(w, cfg);
    auto frames = sparsebody_test::session({{Phase::Stand, 3.0, 1.75}}, 30.0);
    sparsebody_test::reach_out(frames, 1.0, 0.50);
    for (const auto& f : frames) p.push(f);
    REQUIRE(p.calibration_report().status == features::CalibrationStatus::Calibrated);
    *gap = 0;
    for (int side = 0; side < 2; ++side) {
      trackers::PoseD c;
      c.position = trackers::to_eigen(frames.back().pose[1 + side].position);
      c.orientation = trackers::to_eigen(frames.back().pose[1 + side].orientation);
      const Eigen::Vector3d target = p.calibration().apply(1 + side, c).p;
      const int hand = p.skeleton().find(side == 0 ? "Hand_L" : "Hand_R");
      *gap = std::max(*gap, (p.world().position[hand] - target).norm());
    }
    *arm = p.body_proportions().arm;
    const int lower = p.skeleton().find("LowerArm_L");
    CHECK(p.skeleton().offsets[lower].norm() == doctest::Approx(*arm * p.standard_skeleton().offsets[lower].norm()));
    p.recalibrate();  // a new user: the standard arms
    CHECK(p.body_proportions().arm == 1.0);
    CHECK(p.skeleton().offsets[lower] == p.standard_skeleton().offsets[lower]);
  };
  double gap_fit, gap_std, arm_fit, arm_std;
  run(true, &gap_fit, &arm_fit);
  run(false, &gap_std, &arm_std);
  MESSAGE("arm ratio " << arm_fit << ", hands short of the controllers by " << gap_std << " m with the standard arms");
  CHECK(arm_std == 1.0);
  CHECK(gap_std > 0.02);
  CHECK(arm_fit > 1.03);
  CHECK(arm_fit < 1.12);
  CHECK(gap_fit < 0.005);
}

TEST_CASE("n3p default weights: an application's proportions give the arms only (the predictor's torso and legs are standard)") {
  Paper p(Paper::load(prefix()));
  pose::BodyProportions b;
  b.leg = 1.1, b.torso = 1.2, b.arm = 1.1;
  p.set_body_proportions(b);
  CHECK(p.body_proportions().leg == 1.0);
  CHECK(p.body_proportions().torso == 1.0);
  CHECK(p.body_proportions().arm == doctest::Approx(1.1));
  const int lower = p.skeleton().find("LowerArm_L"), spine = p.skeleton().find("Spine");
  CHECK(p.skeleton().offsets[lower].norm() == doctest::Approx(1.1 * p.standard_skeleton().offsets[lower].norm()));
  CHECK(p.skeleton().offsets[spine] == p.standard_skeleton().offsets[spine]);
  p.recalibrate();
  CHECK(p.body_proportions().standard());
}

TEST_CASE("n3p default weights: a folder loads the n3p_*.json set inside it (the demo's --weights DIR)") {
  const std::string dir = std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights";
  const auto ref = Paper::load(prefix());
  for (const std::string& path : {dir, dir + "/"}) {
    const auto w = Paper::load(path);
    CHECK(w.lo->info().kind == "n3p_lower");
    CHECK(w.up->info().kind == "n3p_upper");
    CHECK(w.sig->info().meta.dump() == ref.sig->info().meta.dump());
  }
  // a folder without the set names the file it looked for
  try {
    (void)Paper::load(std::string(SPARSEBODY_SOURCE_DIR) + "/tests");
    FAIL("no LoadError");
  } catch (const LoadError& e) {
    CHECK(std::string(e.what()).find("tests/n3p_signal.json") != std::string::npos);
  }
}

// The user takes the headset off mid-session and puts it and both controllers on a table for 10 s
// (lying face down, 0.8 m high, in front of where they stood; the belt stays on), then puts
// everything back on. The device session of the CMU clip 01_01 (72 Hz), LoBSTr and Neural3Points
// with the shipped weights: the still, low headset on the table is no standing user, so the
// calibration keeps what it found before; no output is non-finite; and 3 s after the headset is
// back the avatar is where the same session without the break puts it. The physics modes
// (Neural3Points' normal mode, QuestSim) keep their calibration and finite output.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/avatar/questsim_session.hpp"
#include "support/device_session.hpp"

using namespace sparsebody;

namespace {

constexpr double kAt = 4.0, kOff = 12.0;  // s: the break starts 1.5 s after the stand, 10 s on the table

// The session with the break at kAt: 1 s to the table, 10 s there, 1 s back; later frames kOff later.
// Returns the frames and, through `inserted`, how many were added.
std::vector<trackers::TrackerFrame> with_break(const std::vector<trackers::TrackerFrame>& s, std::size_t& inserted) {
  std::size_t cut = 0;
  while (cut + 1 < s.size() && s[cut + 1].time <= kAt) ++cut;
  const trackers::TrackerFrame& at = s[cut];
  const double dt = s[cut].time - s[cut - 1].time;
  const Eigen::Vector3d head = trackers::to_eigen(at.pose[0].position);
  const Eigen::Vector3d table[3] = {Eigen::Vector3d(head.x(), 0.80, head.z() - 0.6),
                                    Eigen::Vector3d(head.x() - 0.2, 0.78, head.z() - 0.55),
                                    Eigen::Vector3d(head.x() + 0.2, 0.78, head.z() - 0.55)};
  const Eigen::Quaterniond face_down(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));
  std::vector<trackers::TrackerFrame> out(s.begin(), s.begin() + static_cast<long>(cut) + 1);
  const int n = static_cast<int>(kOff / dt);
  for (int i = 1; i <= n; ++i) {
    trackers::TrackerFrame f = at;
    f.time = at.time + i * dt;
    const double a = std::min({1.0, i * dt / 1.0, (n - i) * dt / 1.0});  // 0 on the user, 1 on the table
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = (1 - a) * trackers::to_eigen(at.pose[k].position) + a * table[k];
      const Eigen::Quaterniond q = Eigen::Quaterniond::Identity().slerp(a, face_down) * trackers::to_eigen(at.pose[k].orientation);
      f.pose[k] = {trackers::to_xr(q), trackers::to_xr(p)};
    }
    out.push_back(f);
  }
  inserted = static_cast<std::size_t>(n);
  for (std::size_t i = cut + 1; i < s.size(); ++i) {
    out.push_back(s[i]);
    out.back().time += kOff;
  }
  return out;
}

// physics: a simulated avatar (chaotic: two runs part after any difference), so only the
// calibration and finite output are compared.
template <class P, class W>
void check_break(const W& w, const char* name, bool physics = false) {
  const auto& plain = sparsebody_test::device_session_01_01();
  std::size_t inserted = 0;
  const auto broken = with_break(plain, inserted);
  P a(w), b(w);
  std::vector<std::vector<Eigen::Vector3d>> at_plain(plain.size());
  for (std::size_t i = 0; i < plain.size(); ++i) {
    a.push(plain[i]);
    if (a.has_output()) at_plain[i] = a.world().position;
  }
  double sum = 0;
  int n = 0, nonfinite = 0;
  const double back = kAt + kOff + 3.0;
  for (std::size_t i = 0; i < broken.size(); ++i) {
    b.push(broken[i]);
    if (!b.has_output()) continue;
    for (const auto& p : b.world().position) nonfinite += !p.allFinite();
    if (broken[i].time < back || i < inserted) continue;
    const auto& q = at_plain[i - inserted];
    if (q.empty()) continue;
    double d = 0;
    for (std::size_t j = 0; j < q.size(); ++j) d += (b.world().position[j] - q[j]).norm();
    sum += d / static_cast<double>(q.size());
    ++n;
  }
  const auto &ra = a.calibration_report(), &rb = b.calibration_report();
  MESSAGE(std::string(name) << ": headset 10 s on a table; stature " << rb.stature << " m (without the break " << ra.stature << "), "
               << rb.windows << " window(s); from 3 s after the return " << 100 * sum / std::max(1, n) << " cm from the run without it ("
               << n << " frames)");
  CHECK(nonfinite == 0);
  REQUIRE(ra.status == features::CalibrationStatus::Calibrated);
  CHECK(rb.status == features::CalibrationStatus::Calibrated);
  CHECK(rb.stature == doctest::Approx(ra.stature).epsilon(1e-9));
  CHECK(rb.windows == ra.windows);
  if (physics) return;
  CHECK(n > 200);
  CHECK(sum / n < 0.03);
}

}  // namespace

TEST_CASE("headset and controllers on a table for 10 s: the calibration stays, the avatar comes back") {
  const std::string dir = SPARSEBODY_WEIGHTS_DIR;
  check_break<avatar::LoBSTrCompact>(avatar::LoBSTrCompact::load(dir + "/lobstr_compact.weights.json"), "LoBSTr");
  check_break<avatar::N3PDirect>(avatar::N3PDirect::load(dir + "/n3p"), "Neural3Points");
}

TEST_CASE("headset on a table for 10 s, physics modes: the calibration stays, the output stays finite") {
  const std::string dir = SPARSEBODY_WEIGHTS_DIR;
  check_break<avatar::N3PPhysicsDefaultSizes<float>>(avatar::N3PDirect::load(dir + "/n3p"), "Neural3Points physics", true);
  check_break<avatar::QuestSimSessionDefault>(avatar::QuestSimSessionDefault::load(dir + "/questsim_policy.json"), "QuestSim", true);
}

// Bit-identical output: the same tracker stream through fresh instances, through instances on
// several threads sharing one weight set, through the pipeline twice in one instance (reset in
// between), and replayed from a recorded tracker CSV, for every weight storage. The stream has the
// events a session has: dropouts, NaN, a gap, a teleport, time going back.
#include <doctest/doctest.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/nn/half.hpp"
#include "sparsebody/nn/int8.hpp"
#include "sparsebody/recordings/tracker_csv.hpp"

using namespace sparsebody;

namespace {

// 12 s of a user walking a circle with swinging hands at 72 Hz, with events.
std::vector<trackers::TrackerFrame> session() {
  std::vector<trackers::TrackerFrame> out;
  double t = 0;
  for (int k = 0; k < 864; ++k) {
    t += 1.0 / 72 * (1 + 0.2 * std::sin(0.37 * k));  // jittered rate
    if (k == 400) t += 2.0;                          // a 2 s gap
    if (k == 600) t -= 0.5;                          // time going back
    const double a = 0.4 * t, s = std::sin(2 * M_PI * 0.9 * t);
    const Eigen::Vector3d c(1.5 * std::sin(a) + (k >= 700 ? 4.0 : 0.0), 0, 1.5 * std::cos(a));  // teleport at 700
    const Eigen::Quaterniond yaw(Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitY()));
    trackers::TrackerFrame f;
    f.time = t;
    const Eigen::Vector3d p[4] = {c + Eigen::Vector3d(0, 1.40 + 0.01 * s, 0), c + yaw * Eigen::Vector3d(0.2, 0.8, 0.15 * s),
                                  c + yaw * Eigen::Vector3d(-0.2, 0.8, -0.15 * s), c + Eigen::Vector3d(0, 0.92, 0)};
    for (int j = 0; j < 4; ++j) {
      f.pose[j].position = trackers::to_xr(p[j]);
      f.pose[j].orientation = trackers::to_xr(yaw);
      f.valid[j] = true;
    }
    if (k >= 200 && k < 230) f.valid[1] = false;                          // controller dropout
    if (k >= 300 && k < 305) f.pose[0].position.y = std::nanf("");        // NaN burst on the headset
    if (k >= 500 && k < 520) f.valid[0] = k % 2 == 0;                     // validity flapping
    out.push_back(f);
  }
  return out;
}

// FNV-1a over the bytes of every output world pose (positions and rotations).
struct Digest {
  std::uint64_t h = 1469598103934665603ull;
  long long outputs = 0;
  void add(const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
  template <class P>
  void add_output(const P& pipe) {
    if (!pipe.has_output()) return;
    ++outputs;
    for (const auto& x : pipe.world().position) add(x.data(), sizeof(double) * 3);
    for (const auto& q : pipe.world().rotation) add(q.coeffs().data(), sizeof(double) * 4);
  }
};

template <class P>
Digest run(P& pipe, const std::vector<trackers::TrackerFrame>& frames) {
  Digest d;
  for (const auto& f : frames)
    if (pipe.push(f) > 0) d.add_output(pipe);
  return d;
}

const std::string kDir = SPARSEBODY_WEIGHTS_DIR;

template <class P, class W>
void check_pipeline(const W& weights, const char* name) {
  INFO(name);
  const auto frames = session();
  P a(weights), b(weights);
  const Digest da = run(a, frames), db = run(b, frames);
  REQUIRE(da.outputs > 300);
  CHECK(da.h == db.h);  // two instances
  a.reset();
  CHECK(run(a, frames).h == da.h);  // one instance again after reset()
  // threads sharing the weights, started together
  std::vector<Digest> dt(4);
  std::vector<std::thread> th;
  for (int i = 0; i < 4; ++i)
    th.emplace_back([&, i] {
      P p(weights);
      dt[i] = run(p, frames);
    });
  for (auto& t : th) t.join();
  for (const auto& d : dt) CHECK(d.h == da.h);
  // replay: the session recorded as a tracker CSV and read back
  std::stringstream csv;
  recordings::write_tracker_csv(csv, frames, "determinism test");
  const auto replayed = recordings::parse_tracker_csv(csv, "replay.csv");
  REQUIRE(replayed.size() == frames.size());
  bool same_input = true;
  for (std::size_t i = 0; i < frames.size(); ++i)
    same_input &= std::memcmp(&frames[i].time, &replayed[i].time, sizeof(double)) == 0 &&
                  std::memcmp(frames[i].pose.data(), replayed[i].pose.data(), sizeof(frames[i].pose)) == 0 &&
                  frames[i].valid == replayed[i].valid;
  CHECK(same_input);
  P r(weights);
  CHECK(run(r, replayed).h == da.h);
}

template <class W>
using LoBSTr = avatar::LoBSTrPipeline<float, 256, 128, W>;
template <class W>
using N3P = avatar::N3PPipeline<float, 64, 128, 128, W>;
template <class W>
using Physics = avatar::N3PPhysicsPipeline<float, 64, 128, 128, float, 24, 72, W>;

template <class W>
std::uint64_t digest_all(std::string& report) {
  const auto frames = session();
  std::uint64_t h = 0;
  auto note = [&](const char* name, const Digest& d) {
    char line[128];
    std::snprintf(line, sizeof line, "%s %016llx %lld\n", name, static_cast<unsigned long long>(d.h), d.outputs);
    report += line;
    h ^= d.h;
  };
  {
    LoBSTr<W> p(LoBSTr<W>::load(kDir + "/lobstr_compact.weights.json"));
    note("lobstr", run(p, frames));
  }
  const auto nw = N3P<W>::load(kDir + "/n3p");
  {
    N3P<W> p(nw);
    note("n3p_direct", run(p, frames));
  }
  if constexpr (!std::is_same_v<W, nn::f16>) {  // the physics pipeline ships float and int8 weights
    Physics<W> p(nw);
    note("n3p_physics", run(p, frames));
  }
  return h;
}

}  // namespace

TEST_CASE_TEMPLATE("LoBSTr output is bit-identical across instances, threads, reset and replay", W, float, nn::f16, nn::q8) {
  check_pipeline<LoBSTr<W>>(LoBSTr<W>::load(kDir + "/lobstr_compact.weights.json"), "lobstr");
}

TEST_CASE_TEMPLATE("Neural3Points direct output is bit-identical across instances, threads, reset and replay", W, float,
                   nn::f16, nn::q8) {
  check_pipeline<N3P<W>>(N3P<W>::load(kDir + "/n3p"), "n3p direct");
}

TEST_CASE_TEMPLATE("Neural3Points physics output is bit-identical across instances, threads, reset and replay", W, float,
                   nn::q8) {
  check_pipeline<Physics<W>>(N3P<W>::load(kDir + "/n3p"), "n3p physics");
}

// Across runs: each CTest run writes this digest; determinism_across_runs compares the files.
TEST_CASE("digest of every pipeline and storage for the across-runs comparison") {
  std::string report;
  digest_all<float>(report);
  digest_all<nn::f16>(report);
  digest_all<nn::q8>(report);
  MESSAGE(report);
  if (const char* out = std::getenv("SPARSEBODY_DIGEST_OUT")) {
    std::ofstream f(out);
    REQUIRE(f);
    f << report;
  }
}

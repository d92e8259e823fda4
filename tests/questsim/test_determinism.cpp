// QuestSim determinism (issue 16, with tests/determinism for the kinematic pipelines): the same
// tracker stream gives bit-identical simulated bodies across instances, after reset(), on threads
// sharing one policy, and replayed from a recorded tracker CSV, for float, f16 and int8 policy
// weights. The stream has dropouts, NaN, a lost headset (reset), a teleport and time going back.
#include <cstdint>
#include <cstring>
#include <sstream>
#include <thread>
#include <vector>

#include "questsim/common.hpp"
#include "sparsebody/recordings/tracker_csv.hpp"

using namespace sparsebody;
using namespace sparsebody::avatar;

namespace {

std::vector<trackers::TrackerFrame> session() {
  std::vector<trackers::TrackerFrame> out;
  double t = 0;
  for (int k = 0; k < 6 * 72; ++k) {
    t += 1.0 / 72 * (1 + 0.2 * std::sin(0.37 * k));
    if (k == 300) t -= 0.4;  // time going back
    trackers::TrackerFrame f = questsim_test::user_frame(t, 1.70, k >= 360 ? 3.0 : 0.3);  // teleport at 360
    if (k >= 60 && k < 80) f.valid[1] = false;                       // controller dropout
    if (k >= 120 && k < 124) f.pose[0].position.y = std::nanf("");   // NaN burst on the headset
    if (k >= 200 && k < 250) f.valid[0] = false;                     // headset lost > 0.5 s: reset
    out.push_back(f);
  }
  return out;
}

// FNV-1a over every body's world pose after every control tick.
template <class C>
std::uint64_t run(C& c, const std::vector<trackers::TrackerFrame>& frames, long long* ticks = nullptr) {
  std::uint64_t h = 1469598103934665603ull;
  auto add = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  };
  long long n = 0;
  for (const auto& f : frames) {
    if (c.push(f) == 0) continue;
    ++n;
    const auto& d = c.simulator().data();
    for (int i = 0; i < c.simulator().model().nb; ++i) {
      add(d.p[i].data(), sizeof(d.p[i](0)) * 3);
      add(d.R[i].data(), sizeof(d.R[i](0)) * 9);
    }
  }
  if (ticks) *ticks = n;
  return h;
}

template <class C>
void check() {
  const auto w = C::load_weights(questsim_test::policy_path());
  const auto frames = session();
  C a(w, 1.70), b(w, 1.70);
  long long ticks = 0;
  const std::uint64_t ha = run(a, frames, &ticks);
  REQUIRE(ticks > 100);
  CHECK(run(b, frames) == ha);  // two instances
  a.reset();
  CHECK(run(a, frames) == ha);  // one instance again after reset()
  std::vector<std::uint64_t> ht(3);
  std::vector<std::thread> th;
  for (int i = 0; i < 3; ++i)
    th.emplace_back([&, i] {
      C c(w, 1.70);
      ht[i] = run(c, frames);
    });
  for (auto& t : th) t.join();
  for (auto x : ht) CHECK(x == ha);  // threads sharing one policy
  std::stringstream csv;
  recordings::write_tracker_csv(csv, frames, "questsim determinism");
  const auto replayed = recordings::parse_tracker_csv(csv, "replay.csv");
  REQUIRE(replayed.size() == frames.size());
  C r(w, 1.70);
  CHECK(run(r, replayed) == ha);  // replayed session
}

}  // namespace

TEST_CASE("QuestSim output is bit-identical across instances, reset, threads and replay (float, f16, int8 policy)") {
  check<QuestSimDefault>();
  check<QuestSimF16>();
  check<QuestSimQ8>();
}

// The Python module's batch loop (weights_tool/native/batch_run.hpp) over the shipped pipelines:
// no allocation inside run_batch (the arrays are numpy's, made before the GIL is released), rows
// equal to pushing the frames one by one, and check_batch's one-line answers to bad batches.
#include <doctest/doctest.h>

#include <cstring>
#include <limits>
#include <vector>

#include "batch_run.hpp"
#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "support/alloc_counter.hpp"
#include "support/standing_stream.hpp"

using namespace sparsebody;

namespace {
// A session as the module receives it: flat arrays [T], [T,4,3], [T,4,4], [T,4].
struct Flat {
  std::vector<double> time;
  std::vector<float> pos, quat;
  std::vector<char> valid;  // bool storage without std::vector<bool>'s packing
  pymod::FrameBatch batch(long from, long n) const {
    pymod::FrameBatch b;
    b.T = n, b.K = 4, b.time = time.data() + from, b.position = pos.data() + from * 12;
    b.orientation = quat.data() + from * 16, b.valid = reinterpret_cast<const bool*>(valid.data()) + from * 4;
    return b;
  }
};

Flat flatten(const std::vector<trackers::TrackerFrame>& fr) {
  Flat f;
  for (const auto& x : fr) {
    f.time.push_back(x.time);
    for (int k = 0; k < 4; ++k) {
      const auto& p = x.pose[k];
      f.pos.insert(f.pos.end(), {p.position.x, p.position.y, p.position.z});
      f.quat.insert(f.quat.end(), {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w});
      f.valid.push_back(x.valid[k]);
    }
  }
  return f;
}

struct Rows {
  std::vector<double> position, rotation, world_rotation, root, prob, user, time, force, torque;
  std::vector<char> contact, locked, has, still;
  std::vector<std::int32_t> steps;
  std::vector<std::int8_t> calib;
  std::vector<std::int64_t> falls;
  Rows(long T, int J)
      : position(T * J * 3), rotation(T * J * 4), world_rotation(T * J * 4), root(T * 3), prob(T * 2), user(T), time(T),
        force(T), torque(T), contact(T * 2), locked(T * 2), has(T), still(T), steps(T), calib(T), falls(T) {}
  pymod::OutputBatch out(long from, int J) {
    pymod::OutputBatch o;
    o.position = position.data() + from * J * 3, o.rotation = rotation.data() + from * J * 4;
    o.world_rotation = world_rotation.data() + from * J * 4, o.root = root.data() + from * 3;
    o.contact_probability = prob.data() + from * 2, o.user_scale = user.data() + from, o.time = time.data() + from;
    o.residual_force = force.data() + from, o.residual_torque = torque.data() + from;
    o.contact = reinterpret_cast<bool*>(contact.data()) + from * 2, o.foot_locked = reinterpret_cast<bool*>(locked.data()) + from * 2;
    o.has_output = reinterpret_cast<bool*>(has.data()) + from, o.standing_still = reinterpret_cast<bool*>(still.data()) + from;
    o.steps = steps.data() + from, o.calibration = calib.data() + from, o.falls = falls.data() + from;
    return o;
  }
};

// Bitwise equality, NaN included (rows without an output are NaN by design).
template <class V>
bool same_bits(const V& a, const V& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
}

std::vector<trackers::TrackerFrame> walk_stand_walk() {
  using sparsebody_test::Phase;
  return sparsebody_test::session({{Phase::Walk, 1.0, 1.62}, {Phase::Stand, 2.0, 1.62}, {Phase::Walk, 2.0, 1.62}}, 72.0);
}

// One batch, no allocation inside; then the same frames in uneven batches give the same rows.
template <class P, class W>
void check_pipeline(const W& w) {
  const Flat in = flatten(walk_stand_walk());
  const long T = static_cast<long>(in.time.size());
  P a(w);
  const int J = a.skeleton().size();
  Rows one(T, J), split(T, J);
  double tick = std::numeric_limits<double>::quiet_NaN();
  {
    sparsebody_test::AllocationCounter c;
    pymod::run_batch(a, in.batch(0, T), one.out(0, J), tick);
    CHECK(c.count() == 0);
  }
  long stepped = 0, shown = 0;
  for (long t = 0; t < T; ++t) stepped += one.steps[t], shown += one.has[t];
  CHECK(stepped > T / 3);  // 72 Hz in, 30 Hz model
  CHECK(shown > T / 2);
  CHECK(one.calib.back() == static_cast<std::int8_t>(features::CalibrationStatus::Calibrated));  // the 2 s stand was found
  P b(w);
  double tick_b = std::numeric_limits<double>::quiet_NaN();
  for (long from = 0, n = 1; from < T; from += n, n = n * 3 + 1) {
    n = std::min(n, T - from);
    pymod::run_batch(b, in.batch(from, n), split.out(from, J), tick_b);
  }
  CHECK(same_bits(one.position, split.position));
  CHECK(same_bits(one.rotation, split.rotation));
  CHECK(same_bits(one.force, split.force));
  CHECK(same_bits(one.contact, split.contact));
}
}  // namespace

TEST_CASE("pymod batches: LoBSTr, Neural3Points direct and physics allocate nothing and split freely") {
  const std::string dir = SPARSEBODY_SOURCE_DIR "/examples/weights/";
  SUBCASE("LoBSTr") { check_pipeline<avatar::LoBSTrCompact>(avatar::LoBSTrCompact::load(dir + "lobstr_compact.weights.json")); }
  SUBCASE("Neural3Points direct") { check_pipeline<avatar::N3PDirect>(avatar::N3PDirect::load(dir + "n3p")); }
  SUBCASE("Neural3Points physics") { check_pipeline<avatar::N3PPhysicsDefault>(avatar::N3PPhysicsDefault::load(dir + "n3p")); }
}

TEST_CASE("pymod check_batch names the first bad frame in one line") {
  Flat in = flatten(walk_stand_walk());
  char msg[256];
  CHECK(pymod::check_batch(in.batch(0, 10), -std::numeric_limits<double>::infinity(), msg, sizeof msg));
  CHECK(msg[0] == '\0');
  in.pos[3 * 12 + 1 * 3 + 2] = std::numeric_limits<float>::quiet_NaN();  // frame 3, left hand z
  CHECK_FALSE(pymod::check_batch(in.batch(0, 10), -std::numeric_limits<double>::infinity(), msg, sizeof msg));
  CHECK(std::string(msg).find("frame 3, tracker 1 (left_hand): position is nan") == 0);
  in.valid[3 * 4 + 1] = 0;  // the same NaN in a pose marked invalid: fine
  CHECK(pymod::check_batch(in.batch(0, 10), -std::numeric_limits<double>::infinity(), msg, sizeof msg));
  in.time[5] = in.time[4];
  CHECK_FALSE(pymod::check_batch(in.batch(0, 10), -std::numeric_limits<double>::infinity(), msg, sizeof msg));
  CHECK(std::string(msg).find("frame 5: timestamp") == 0);
  CHECK_FALSE(pymod::check_batch(in.batch(0, 3), 100.0, msg, sizeof msg));  // before the previous batch's last time
  CHECK(std::strchr(msg, '\n') == nullptr);
}

// Soak run: hours of input through one pipeline (validation clips joined end to end, with the
// events of soak_stream.hpp), checking what a long headset session needs:
//   - no non-finite value in any output;
//   - no heap allocation in push() after the warm-up (the first minute of input);
//   - resident memory flat after the warm-up (growth reported; the check allows < 1 MB);
//   - the avatar's head stays near the headset: horizontal distance, outside the 5 s after an event;
//   - falls, resets and failed simulation steps counted.
// Usage:
//   sparsebody_soak --pipeline lobstr|n3p|n3p_physics|questsim --clips DIR [--hours H | --minutes M]
//                   [--seed N] [--storage float|f16|q8] [--questsim-policy FILE (default: the shipped one)] [--json FILE]
// Exit codes: 0 all checks passed, 1 a check failed, 2 bad command line or input.
// SOAK_TRACE=1 in the environment prints one line per output: input time, event, head distance,
// whether it counts (outside the quiet window after an event).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <type_traits>
#include <algorithm>

#include "soak_checks.hpp"
#include "soak_clips.hpp"
#include "soak_pipelines.hpp"
#include "soak_stream.hpp"
#include "support/alloc_counter.hpp"

namespace {

struct Options {
  std::string pipeline, clips, storage = "float", questsim_policy, json;
  double hours = 0;
  std::uint64_t seed = 1;
};

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "error: %s\nusage: sparsebody_soak --pipeline lobstr|n3p|n3p_physics|questsim --clips DIR\n"
               "       [--hours H | --minutes M] [--seed N] [--storage float|f16|q8] [--questsim-policy FILE] [--json FILE]\n",
               why);
  std::exit(2);
}

double number(const char* flag, const char* v) {
  char* end = nullptr;
  const double x = std::strtod(v, &end);
  if (end == v || *end != '\0' || !(x > 0)) usage((std::string(flag) + ": expected a positive number, got '" + v + "'").c_str());
  return x;
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) usage((a + ": missing value").c_str());
      return argv[++i];
    };
    if (a == "--pipeline") o.pipeline = value();
    else if (a == "--clips") o.clips = value();
    else if (a == "--hours") o.hours = number("--hours", value());
    else if (a == "--minutes") o.hours = number("--minutes", value()) / 60;
    else if (a == "--seed") o.seed = static_cast<std::uint64_t>(number("--seed", value()));
    else if (a == "--storage") o.storage = value();
    else if (a == "--questsim-policy") o.questsim_policy = value();
    else if (a == "--json") o.json = value();
    else usage(("unknown option '" + a + "'").c_str());
  }
  if (o.pipeline.empty() || o.clips.empty() || !(o.hours > 0)) usage("--pipeline, --clips and --hours/--minutes are required");
  if (o.storage != "float" && o.storage != "f16" && o.storage != "q8") usage("--storage: expected float, f16 or q8");
  if (o.pipeline == "questsim" && o.questsim_policy.empty()) o.questsim_policy = SPARSEBODY_DEFAULT_QUESTSIM_WEIGHTS;
  return o;
}

// Runs the stream through one pipeline adapter (soak_pipelines.hpp) and fills the report.
template <class Adapter>
soak::Report run(Adapter& pipe, const std::vector<soak::Clip>& clips, const Options& o) {
  soak::Stream stream(clips, o.seed);
  soak::Report r;
  r.pipeline = o.pipeline + " (" + o.storage + ")";
  const double total = o.hours * 3600, warmup = 60;
  double quiet_until = 0, next_progress = 600;
  long long rss_after_warmup = -1;
  const auto wall0 = soak::now();
  const bool trace = std::getenv("SOAK_TRACE") != nullptr;
  while (stream.input_seconds() < total) {
    const soak::StreamFrame s = stream.next();
    const double t = stream.input_seconds();
    if (s.event >= 0) quiet_until = std::max(quiet_until, t + (s.recalibrate ? 15.0 : 5.0));  // a recalibration lasts 10 s
    if (s.recalibrate) pipe.calibrate_on(s.frame);
    if (s.restore) pipe.restore_calibration();
    if (s.skip) continue;
    const bool counting = t > warmup;
    if (counting && rss_after_warmup < 0) rss_after_warmup = soak::resident_bytes();
    int ticks;
    {
      sparsebody_test::AllocationCounter count;
      ticks = pipe.push(s.frame);
      if (counting) r.allocations += count.count();
    }
    if (ticks == 0) continue;
    r.outputs += ticks;
    if (!pipe.output_finite()) ++r.non_finite;
    if (t > quiet_until && t > 5) r.drift.add(pipe.head_distance(s.frame));
    if (trace) std::fprintf(stderr, "trace %.3f %d %.3f %d\n", t, s.event, pipe.head_distance(s.frame), int(t > quiet_until && t > 5));
    if (t >= next_progress) {
      next_progress += 600;
      std::fprintf(stderr, "[soak %s] %.2f / %.2f h of input, %.0f s wall, %lld non-finite, %lld allocations, rss %+.2f MB, drift p99 %.3f m\n",
                   r.pipeline.c_str(), t / 3600, o.hours, soak::seconds_since(wall0), r.non_finite, r.allocations,
                   rss_after_warmup < 0 ? 0.0 : (soak::resident_bytes() - rss_after_warmup) / 1e6, r.drift.quantile(0.99));
    }
  }
  r.input_hours = stream.input_seconds() / 3600;
  r.wall_seconds = soak::seconds_since(wall0);
  r.rss_growth_bytes = rss_after_warmup < 0 ? 0 : soak::resident_bytes() - rss_after_warmup;
  r.events = stream.event_counts();
  pipe.counters(r);
  return r;
}

template <class Adapter, class... A>
int soak_with(const std::vector<soak::Clip>& clips, const Options& o, A&&... args) {
  Adapter pipe(std::forward<A>(args)...);
  const soak::Report r = run(pipe, clips, o);
  r.print(stdout);
  if (!o.json.empty()) r.write_json(o.json);
  return r.passed() ? 0 : 1;
}

template <class W>
int dispatch(const std::vector<soak::Clip>& clips, const Options& o, double clip_leg) {
  if (o.pipeline == "lobstr") return soak_with<soak::LoBSTrAdapter<W>>(clips, o, clip_leg);
  if (o.pipeline == "n3p") return soak_with<soak::N3PAdapter<W>>(clips, o, clip_leg);
  if (o.pipeline == "n3p_physics") {
    if constexpr (std::is_same_v<W, sparsebody::nn::f16>) usage("n3p_physics: storage float or q8");
    else return soak_with<soak::N3PPhysicsAdapter<W>>(clips, o, clip_leg);
  }
  if (o.pipeline == "questsim") return soak_with<soak::QuestSimAdapter<W>>(clips, o, o.questsim_policy);
  usage(("unknown pipeline '" + o.pipeline + "'").c_str());
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  try {
    double leg = 0;
    const std::vector<soak::Clip> clips = soak::load_clips(o.clips, leg);
    std::printf("soak    %s, %zu clips from %s (leg %.3f m), %.2f h of input, seed %llu\n", o.pipeline.c_str(), clips.size(),
                o.clips.c_str(), leg, o.hours, static_cast<unsigned long long>(o.seed));
    if (o.storage == "f16") return dispatch<sparsebody::nn::f16>(clips, o, leg);
    if (o.storage == "q8") return dispatch<sparsebody::nn::q8>(clips, o, leg);
    return dispatch<float>(clips, o, leg);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
}

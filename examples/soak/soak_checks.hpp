// What the soak run measures and reports: resident memory, a fixed-size histogram of the head's
// distance from the headset (no allocation while running), counters, the pass/fail rule.
#pragma once
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "soak_stream.hpp"

namespace soak {

inline long long resident_bytes() {
  std::ifstream f("/proc/self/statm");
  long long pages = 0, resident = 0;
  f >> pages >> resident;
  return resident * sysconf(_SC_PAGESIZE);
}

using Clock = std::chrono::steady_clock;
inline Clock::time_point now() { return Clock::now(); }
inline double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Distances 0..10 m in 1 mm bins (more goes into the last bin); mean and max exact.
struct Histogram {
  std::array<long long, 10001> bins{};
  long long n = 0;
  double sum = 0, max = 0;
  void add(double d) {
    if (!(d >= 0)) d = 10;  // a NaN distance counts as the worst
    ++n;
    sum += d;
    max = std::max(max, d);
    ++bins[std::min<std::size_t>(bins.size() - 1, static_cast<std::size_t>(d * 1000))];
  }
  double mean() const { return n ? sum / n : 0; }
  double quantile(double q) const {
    if (!n) return 0;
    long long need = static_cast<long long>(q * n), seen = 0;
    for (std::size_t i = 0; i < bins.size(); ++i)
      if ((seen += bins[i]) > need) return (i + 1) / 1000.0;
    return 10;
  }
};

struct Report {
  static constexpr long long kMaxRssGrowth = 1 << 20;  // 1 MB
  // Head vs headset, horizontal, away from events: p99 bound (m) set per pipeline by its adapter;
  // negative: reported, not checked (the shipped QuestSim policy still falls ~33 times a minute).
  double max_drift_p99 = 0.5;

  std::string pipeline;
  double input_hours = 0, wall_seconds = 0;
  long long outputs = 0, non_finite = 0, allocations = 0, rss_growth_bytes = 0;
  long long falls = 0, resets = 0, sim_failures = 0;
  Histogram drift;
  std::vector<long long> events;

  bool passed() const {
    return non_finite == 0 && allocations == 0 && rss_growth_bytes < kMaxRssGrowth &&
           (max_drift_p99 < 0 || drift.quantile(0.99) <= max_drift_p99);
  }

  void print(std::FILE* f) const {
    std::fprintf(f, "result  %s: %.2f h of input in %.0f s (%.0fx real time), %lld outputs\n", pipeline.c_str(), input_hours,
                 wall_seconds, input_hours * 3600 / std::max(wall_seconds, 1e-9), outputs);
    std::fprintf(f, "checks  non-finite outputs %lld, allocations after warm-up %lld, resident memory growth %.3f MB\n", non_finite,
                 allocations, rss_growth_bytes / 1e6);
    std::fprintf(f, "drift   head to headset (horizontal, outside 5 s after events): mean %.3f m, p99 %.3f m, max %.3f m (%s)\n",
                 drift.mean(), drift.quantile(0.99), drift.max,
                 max_drift_p99 < 0 ? "not checked" : ("p99 bound " + std::to_string(max_drift_p99).substr(0, 4) + " m").c_str());
    std::fprintf(f, "counts  falls %lld, resets %lld, failed simulation steps %lld; events:", falls, resets, sim_failures);
    for (std::size_t e = 0; e < events.size(); ++e) std::fprintf(f, " %s %lld", event_name(static_cast<int>(e)), events[e]);
    std::fprintf(f, "\n%s\n", passed() ? "PASS" : "FAIL");
  }

  void write_json(const std::string& path) const {
    std::ofstream o(path);
    o << "{\"pipeline\": \"" << pipeline << "\", \"input_hours\": " << input_hours << ", \"wall_seconds\": " << wall_seconds
      << ", \"outputs\": " << outputs << ", \"non_finite\": " << non_finite << ", \"allocations_after_warmup\": " << allocations
      << ", \"rss_growth_bytes\": " << rss_growth_bytes << ", \"drift_mean_m\": " << drift.mean()
      << ", \"drift_p99_m\": " << drift.quantile(0.99) << ", \"drift_max_m\": " << drift.max << ", \"falls\": " << falls
      << ", \"resets\": " << resets << ", \"sim_failures\": " << sim_failures << ", \"events\": {";
    for (std::size_t e = 0; e < events.size(); ++e) o << (e ? ", " : "") << "\"" << event_name(static_cast<int>(e)) << "\": " << events[e];
    o << "}, \"passed\": " << (passed() ? "true" : "false") << "}\n";
  }
};

}  // namespace soak

// A Google Benchmark main that, after the normal report, prints ratios between benchmarks measured
// in the same run (e.g. sparsebody vs LibTorch, a network vs a plain read of its weight bytes).
// Uses the median aggregate when --benchmark_repetitions > 1, else the single run; CPU time, not
// real time: on a shared machine a descheduled thread inflates real time, not CPU time (both
// benchmarks of a ratio are single-threaded, so CPU time is the time they ran).
#pragma once
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

namespace sparsebody_bench {

struct Ratio {
  std::string label, numerator, denominator;  // benchmark names (without aggregate suffix)
};

inline std::vector<Ratio>& ratios() {
  static std::vector<Ratio> r;
  return r;
}
inline void add_ratio(std::string label, std::string num, std::string den) {
  ratios().push_back({std::move(label), std::move(num), std::move(den)});
}

class CollectingReporter : public benchmark::ConsoleReporter {
 public:
  std::map<std::string, double> times_ns;  // name -> CPU time per iteration (ns)
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.error_occurred) continue;
      const bool aggregate = r.run_type == Run::RT_Aggregate;
      if (aggregate && r.aggregate_name != "median") continue;
      const double ns = r.GetAdjustedCPUTime() * to_ns(r.time_unit);
      const std::string name = r.run_name.str();
      if (aggregate || !times_ns.count(name) || !medians_seen_.count(name)) times_ns[name] = ns;
      if (aggregate) medians_seen_[name] = true;
    }
    ConsoleReporter::ReportRuns(runs);
  }

 private:
  static double to_ns(benchmark::TimeUnit u) {
    switch (u) {
      case benchmark::kSecond: return 1e9;
      case benchmark::kMillisecond: return 1e6;
      case benchmark::kMicrosecond: return 1e3;
      default: return 1.0;
    }
  }
  std::map<std::string, bool> medians_seen_;
};

inline int run_with_ratios(int argc, char** argv, const char* title) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  CollectingReporter rep;
  benchmark::RunSpecifiedBenchmarks(&rep);
  std::printf("\n%s: ratios measured in this run (time of first / time of second)\n", title);
  for (const Ratio& r : ratios()) {
    auto a = rep.times_ns.find(r.numerator), b = rep.times_ns.find(r.denominator);
    if (a == rep.times_ns.end() || b == rep.times_ns.end()) continue;
    std::printf("  %-58s %9.3f us / %9.3f us = %6.3f\n", r.label.c_str(), a->second / 1e3, b->second / 1e3,
                a->second / b->second);
  }
  benchmark::Shutdown();
  return 0;
}

}  // namespace sparsebody_bench

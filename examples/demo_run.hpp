// sparsebody_demo's run of one pipeline over the input, the same for every pipeline (they share
// the front end: push, has_output, pose, world, plus skeleton, joint_map, contact, user_scale,
// calibrate and meta().frame_rate): fitting the user, the frame loop with its progress lines, the
// output BVH, timing, and the metrics against the clip.
#pragma once
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>

#include "demo_input.hpp"
#include "demo_metrics.hpp"
#include "demo_options.hpp"
#include "sparsebody/recordings/bvh.hpp"

namespace demo {

// BVH input: the synthesised trackers are calibrated already, only the size differs, so
// set_scale(s) gets the standard skeleton's / the clip's leg length. CSV input: T-pose calibration
// on --calibration-frame. Prints which; false (after saying why) when the frame cannot be used.
template <class Pipeline, class SetScale>
bool fit_user(const Options& o, const Input& in, Pipeline& pipe, SetScale&& set_scale) {
  if (in.have_truth) {
    const double s = sparsebody::pose::leg_length(pipe.skeleton(), pipe.joint_map()) / in.leg;
    set_scale(s);
    std::printf("scale   %.3f to the standard skeleton (leg length)\n", s);
    return true;
  }
  if (o.calibration_frame < 0 || o.calibration_frame >= static_cast<int>(in.frames.size()) ||
      !pipe.calibrate(in.frames[static_cast<std::size_t>(o.calibration_frame)])) {
    std::fprintf(stderr, "%s: frame %d cannot be used for calibration (headset invalid or too low)\n", o.input.c_str(),
                 o.calibration_frame);
    return false;
  }
  std::printf("calib   T-pose on frame %d, user scale %.3f\n", o.calibration_frame, pipe.user_scale());
  return true;
}

inline void print_credit(const std::string& credit) {
  if (!credit.empty()) std::printf("weights credit: %s\n", credit.c_str());
}

// Seconds since the first input frame of the pose a kinematic pipeline shows now (its last step).
template <class Pipeline>
double last_step_seconds(const Pipeline& p) {
  return p.frames() / p.meta().frame_rate - 1.0 / p.meta().frame_rate;
}

// Feeds every input frame, writes the output BVH and prints progress, output and speed lines.
// shown_seconds(): the clip time of the pose the pipeline shows now. The metrics are empty
// without a clip.
template <class Pipeline, class ShownSeconds>
std::optional<Metrics> stream(const Options& o, Input& in, Pipeline& pipe, ShownSeconds&& shown_seconds) {
  namespace sb = sparsebody;
  const double fps = pipe.meta().frame_rate, user = pipe.user_scale();
  sb::recordings::BvhWriter writer(pipe.skeleton(), 1.0 / fps, 100.0 * user);
  std::optional<Metrics> m;
  if (in.have_truth) m.emplace(pipe.skeleton(), pipe.joint_map(), in, fps);
  double step_seconds = 0;
  long steps = 0;
  const std::size_t n = in.frames.size(), report = std::max<std::size_t>(1, n / 10);
  for (std::size_t i = 0; i < n; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const int k = pipe.push(in.frames[i]);
    step_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    steps += k;
    if (k > 0 && pipe.has_output()) {
      writer.add(pipe.pose(), 100.0 * user);
      const bool contact[2] = {pipe.contact(0), pipe.contact(1)};
      if (m) m->add(pipe.pose(), pipe.world(), user, shown_seconds(), contact);
    }
    if (!o.quiet && (i + 1) % report == 0)
      std::printf("  %3d%%  frame %zu/%zu, %ld model steps, contacts L %s R %s\n", static_cast<int>(100 * (i + 1) / n), i + 1, n,
                  steps, pipe.contact(0) ? "on " : "off", pipe.contact(1) ? "on " : "off");
  }
  writer.write(o.output);
  std::printf("wrote   %s: %ld frames at %.0f fps (standard skeleton at the user's size, centimetres)\n", o.output.c_str(), steps,
              fps);
  std::printf("speed   %.1f us per model step (whole pipeline, this run, including resampling)\n",
              1e6 * step_seconds / std::max(1L, steps));
  return m;
}

}  // namespace demo

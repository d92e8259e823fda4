// sparsebody_demo's run of one pipeline over the input, the same for every pipeline (they share
// the front end: push, has_output, pose, world, plus skeleton, joint_map, contact, user_scale,
// calibrate, calibration_report and meta().frame_rate): fitting the user, the frame loop with its progress lines, the
// output BVH, timing, and the metrics against the clip.
#pragma once
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <cstdio>
#include <optional>
#include <type_traits>
#include <utility>
#include <string>

#include <nlohmann/json.hpp>

#include "demo_input.hpp"
#include "sparsebody/pose/body_proportions.hpp"
#include "demo_metrics.hpp"
#include "demo_options.hpp"
#include "demo_viewer.hpp"
#include "sparsebody/recordings/bvh.hpp"

namespace demo {

// BVH input with trackers at the joints (no --devices): they are calibrated already, only the size
// differs, so set_scale(s) gets the standard skeleton's / the clip's leg length. Otherwise (CSV,
// BVH --devices): --calibration-frame N forces a calibration on input frame N (a T-pose or an
// upright standing frame; its range was checked by main), else the pipeline calibrates itself from
// standing windows while it runs (print_calibration says what it found). Prints which; false
// (after saying why) when the forced frame cannot be used.
template <class Pipeline, class SetScale>
bool fit_user(const Options& o, const Input& in, Pipeline& pipe, SetScale&& set_scale) {
  if (in.at_joints) {
    namespace pose = sparsebody::pose;
    const double s = pose::leg_length(pipe.standard_skeleton(), pipe.joint_map()) / in.leg;
    set_scale(s);
    std::printf("scale   %.3f to the standard skeleton (leg length; trackers at the joints)\n", s);
    // the output skeleton in the clip's proportions (the trackers are its joints)
    const pose::BodyProportions b = pose::proportions_by_leg(
        pose::BodyLengths::of(in.clip.skeleton, pose::JointMap::from_names(in.clip.skeleton, o.input)),
        pose::BodyLengths::of(pipe.standard_skeleton(), pipe.joint_map()));
    pipe.set_body_proportions(b);
    if (!pipe.body_proportions().standard())
      std::printf("body    torso x%.3f, arms x%.3f the standard skeleton's (the clip's proportions)\n", pipe.body_proportions().torso,
                  pipe.body_proportions().arm);
    if (o.calibration_forced) std::printf("note    --calibration-frame is not used: these trackers are synthesised at the joints\n");
    return true;
  }
  if (o.calibration_forced) {
    if (!pipe.calibrate(in.frames[static_cast<std::size_t>(o.calibration_frame)])) {
      std::fprintf(stderr, "%s: frame %ld cannot be used for calibration (headset invalid or too low)\n", o.input.c_str(),
                   o.calibration_frame);
      return false;
    }
    std::printf("calib   forced on frame %ld (--calibration-frame): stature %.2f m, user scale %.3f\n", o.calibration_frame,
                pipe.calibration_report().stature, pipe.user_scale());
    return true;
  }
  std::printf("calib   automatic: searching for standing windows (the default body until one is found)\n");
  return true;
}

// The calibration the run ended with, said honestly: the standing window it found (input frames and
// times), a refusal, or none (the default body). Nothing for trackers at the joints.
// Pipelines with a stand-up detector (trackers/stand_up.hpp; QuestSim has none).
template <class P, class = void>
struct has_stand_ups : std::false_type {};
template <class P>
struct has_stand_ups<P, std::void_t<decltype(std::declval<const P&>().stand_ups())>> : std::true_type {};

template <class Pipeline>
void print_calibration(const Options& o, const Input& in, const Pipeline& pipe) {
  namespace f = sparsebody::features;
  if (in.at_joints || o.calibration_forced) return;
  const f::CalibrationReport& r = pipe.calibration_report();
  if (r.status == f::CalibrationStatus::Calibrated) {
    std::printf("calib   automatic%s: standing at frames %ld-%ld (%.1f-%.1f s), stature %.2f m%s, confidence %.2f",
                r.provisional ? " (provisional: no full 1 s stand yet)" : "", frame_at(in, r.first_time),
                frame_at(in, r.last_time), r.first_time - in.frames.front().time, r.last_time - in.frames.front().time, r.stature,
                r.floor_estimated ? " (assumed)" : "", r.confidence);
    if (r.windows > 1) std::printf(", %d windows averaged", r.windows);
    if (r.skipped > 0) std::printf(", %d lower (sitting?) not used", r.skipped);
    if (r.refused > 0) std::printf(", %d implausible not used", r.refused);
    if (r.grip_default[0] || r.grip_default[1])  // e.g. lying on a table at every stand (max_grip_deviation)
      std::printf(", %s not seen held at a stand (the device model's grip)",
                  r.grip_default[0] && r.grip_default[1] ? "both controllers" : r.grip_default[0] ? "the left controller" : "the right controller");
    if (r.floor_estimated)
      std::printf(", floor estimated at y = %.2f m%s", r.floor,
                  r.floor_not_at_zero ? " (the standing eye height is below 0.5 m: y = 0 is not the floor)" : "");
    std::printf("\n");
    const sparsebody::pose::BodyProportions& b = pipe.body_proportions();
    if (!b.standard())  // LoBSTr with a pelvis tracker (avatar/lobstr_pipeline.hpp fit_body)
      std::printf("body    legs x%.3f, torso x%.3f the standard skeleton's (from the pelvis tracker's standing height)\n", b.leg,
                  b.torso);
  } else if (r.status == f::CalibrationStatus::Refused) {
    std::printf("calib   %s (input frames %ld-%ld)\n", r.message, frame_at(in, r.first_time), frame_at(in, r.last_time));
  } else if (r.sized_from_headset) {  // from the headset height (a lower bound, or QuestSim's estimate), not a calibration
    std::printf("calib   no standing frame found: default body sized to the headset (stature %s%.2f m, not measured)\n",
                r.sized_lower_bound ? ">= " : "~", r.stature);
  } else {
    std::printf("calib   no standing frame found: default body (stature %.2f m)\n", r.stature);
  }
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
  const double fps = pipe.meta().frame_rate;
  sb::recordings::BvhWriter writer(pipe.skeleton(), 1.0 / fps, 100.0 * pipe.user_scale());
  std::optional<Metrics> m;
  if (in.have_truth) m.emplace(pipe.skeleton(), pipe.joint_map(), in, fps);
  double step_seconds = 0;
  long steps = 0;
  const std::size_t n = in.frames.size(), report = std::max<std::size_t>(1, n / 10);
  std::optional<ViewerRecorder> viewer;  // --html: reserved for the whole run up front
  if (!o.html.empty()) {
    viewer.emplace();
    const double seconds = n > 1 ? in.frames.back().time - in.frames.front().time : 0;
    viewer->begin(pipe.skeleton(), pipe.joint_map(), in.have_truth ? &in.clip.skeleton : nullptr,
                  static_cast<std::size_t>(seconds * fps) + 16);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const int k = pipe.push(in.frames[i]);
    step_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    steps += k;
    if (k > 0 && pipe.has_output()) {
      const double user = pipe.user_scale();  // follows the calibration (automatic: it may change)
      writer.add(pipe.pose(), 100.0 * user);
      const bool contact[2] = {pipe.contact(0), pipe.contact(1)};
      if (m) m->add(pipe.pose(), pipe.world(), user, shown_seconds(), contact);
      if (viewer) {  // the trackers and clip frame of the time the pose shows (physics: 0.1 s back)
        const double shown = shown_seconds();
        const sb::trackers::TrackerFrame& trk = in.frames[static_cast<std::size_t>(frame_at(in, in.frames.front().time + shown))];
        int gf = -1;
        if (in.have_truth) {
          gf = std::clamp(static_cast<int>(std::lround(shown / in.clip.frame_time)), 0, in.clip.frames - 1);
          in.truth.at(gf);
        }
        viewer->add(pipe.pose(), user, contact, trk, in.have_truth ? &in.truth.w : nullptr, gf);
      }
    }
    if (!o.quiet && (i + 1) % report == 0)
      std::printf("  %3d%%  frame %zu/%zu, %ld model steps, contacts L %s R %s\n", static_cast<int>(100 * (i + 1) / n), i + 1, n,
                  steps, pipe.contact(0) ? "on " : "off", pipe.contact(1) ? "on " : "off");
  }
  writer.set_offset_scale(100.0 * pipe.user_scale());  // the skeleton at the size the run ended with
  writer.write(o.output);
  std::printf("wrote   %s: %ld frames at %.0f fps (the output skeleton at the user's size, centimetres)\n", o.output.c_str(), steps,
              fps);
  std::printf("speed   %.1f us per model step (whole pipeline, this run, including resampling)\n",
              1e6 * step_seconds / std::max(1L, steps));
  if (pipe.recentres() > 0)
    std::printf("recentre %d recentred tracking space%s (every tracker turned / shifted together between two frames): the model "
                "restarted there\n", pipe.recentres(), pipe.recentres() == 1 ? "" : "s");
  if (pipe.controller_swaps() > 0)
    std::printf("swap    the controllers were held in the other hands (left / right crossed while hanging): exchanged %s%s\n",
                pipe.controllers_swapped() ? "from then on" : "and back", pipe.controller_swaps() > 2 ? " (several times)" : "");
  if constexpr (has_stand_ups<Pipeline>::value) {
    if (pipe.stand_ups() > 0)
      std::printf("stand-up %lld time%s the user stood up from a seat: the model restarted there, the feet unheld for 1 s\n",
                  pipe.stand_ups(), pipe.stand_ups() == 1 ? "" : "s");
  }
  print_calibration(o, in, pipe);
  if (viewer) {
    nlohmann::json info = {{"input", o.input}, {"model", in.model}, {"fps", fps}, {"user_scale", pipe.user_scale()},
                           {"us_per_step", 1e6 * step_seconds / std::max(1L, steps)},
                           {"metrics", m ? nlohmann::json::parse(m->json()) : nlohmann::json(nullptr)}};
    viewer->write(o.html, SPARSEBODY_VIEWER_TEMPLATE, o.three_js, info.dump());
    std::printf("wrote   %s: browser page of %zu frames, %.2f MB (three.js %s inlined)\n", o.html.c_str(), viewer->frames(),
                std::filesystem::file_size(o.html) / 1e6, o.three_js.c_str());
  }
  return m;
}

}  // namespace demo

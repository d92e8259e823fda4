// What a pipeline's calibration is based on, said honestly: no standing frame yet (the default
// body), calibrated (automatically from standing windows, from an explicit frame, or set by the
// application), or refused (a standing window gave a stature outside the plausible range; the
// default body is used). Plain data with a fixed-size message, so reading it never allocates.
#pragma once
#include <cmath>
#include <limits>

namespace sparsebody::features {

enum class CalibrationStatus { Default, Calibrated, Refused };
enum class CalibrationSource { None, Automatic, Explicit, Application };

inline const char* calibration_status_name(CalibrationStatus s) noexcept {
  switch (s) {
    case CalibrationStatus::Default: return "default";
    case CalibrationStatus::Calibrated: return "calibrated";
    default: return "refused";
  }
}

struct CalibrationReport {
  CalibrationStatus status = CalibrationStatus::Default;
  CalibrationSource source = CalibrationSource::None;
  // The window (or frame) the calibration was taken from: model frames counted by the calibrator
  // since the pipeline started or recalibrate(), and the input's time stamps (seconds). For an
  // averaged estimate: the newest window. -1 / NaN when none.
  long long first_frame = -1, last_frame = -1;
  double first_time = std::numeric_limits<double>::quiet_NaN(), last_time = std::numeric_limits<double>::quiet_NaN();
  double stature = 0;     // m: eye height / 0.936 (Winter, Fig. 4.1), or the default body's
  double eye_height = 0;  // m above the floor: median headset height over the window(s)
  double scale = 1;       // s, user -> standard skeleton
  double floor = 0;       // world y of the floor used
  double confidence = 0;  // [0, 1]: window length, stillness, agreement between windows
  bool floor_estimated = false;  // AutoCalibrationConfig::estimate_floor: stature assumed
  // ... because a standing eye height was below floor_fallback_eye: y = 0 is not the floor
  bool floor_not_at_zero = false;
  int windows = 0;   // standing windows in the estimate (averaged)
  int replaced = 0;  // estimates replaced by a window more than 4 cm higher
  int raised = 0;    // estimates raised: the headset stayed above a bent stand's height (AutoCalibration::rise)
  int skipped = 0;   // windows more than 4 cm lower than the estimate (sitting, crouching): not used
  int refused = 0;   // windows whose stature was outside the plausible range: not used
  // windows whose controller (left or right, each counted) was not held as at a stand (e.g. on a
  // table: AutoCalibrationConfig::max_grip_deviation): its offset not taken from them
  int grips_not_held = 0;
  // Calibrated status: the left / right controller still has the device model's orientation offset
  // (no window has seen it held yet)
  bool grip_default[2] = {false, false};
  // The estimate is the first stand's early one (AutoCalibrationConfig::first_window): the window
  // is still open and replaces it when the user stops standing (or after max_window).
  bool provisional = false;
  // Default status only: the default body was enlarged to the first upright headset frame's eye
  // height (AutoCalibrationConfig::size_from_headset): a lower bound on the stature, not a
  // calibration.
  bool sized_from_headset = false;
  // ... as a lower bound (the default); false with size_from_headset_both_ways: an estimate from a
  // frame that need not be standing (up or down).
  bool sized_lower_bound = false;
  char message[192] = "no standing frame yet: default body";  // one line
};

}  // namespace sparsebody::features

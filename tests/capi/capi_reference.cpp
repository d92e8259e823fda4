// The C++ side of the C# test (tests/capi/run_csharp.sh): writes the session CSV the C# program
// streams, reads it back as the demo reads a CSV (recordings::read_tracker_csv), runs it through the
// C++ pipelines with the demo's defaults (automatic calibration, contact IK, float weights) and
// writes, per pushed frame with a pose, the joint world positions in the user's size
// (world() * user_scale(), as float: what sb_pipeline_read gives).
//   capi_reference CLIP.bvh WEIGHTS_DIR OUT_DIR  ->  OUT_DIR/session.csv, OUT_DIR/{lobstr,n3p_direct,n3p_physics}.ref
// Compiled with the C library's ISA flags (SPARSEBODY_C_ISA), not -march=native.
#include <cstdio>
#include <exception>
#include <string>

#include "capi_session.hpp"
#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/recordings/tracker_csv.hpp"

using namespace sparsebody;

namespace {
template <class P>
void run(P& p, const std::vector<trackers::TrackerFrame>& frames, const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error("cannot write " + path);
  long lines = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    p.push(frames[i]);
    if (!p.has_output()) continue;
    const double s = p.user_scale();
    std::fprintf(f, "%zu", i);
    for (const auto& w : p.world().position)
      std::fprintf(f, " %.9g %.9g %.9g", double(float(w.x() * s)), double(float(w.y() * s)), double(float(w.z() * s)));
    std::fprintf(f, "\n");
    ++lines;
  }
  std::fclose(f);
  std::printf("reference %s: %ld frames with a pose of %zu pushed, calibration %s\n", path.c_str(), lines, frames.size(),
              features::calibration_status_name(p.calibration_report().status));
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: capi_reference CLIP.bvh WEIGHTS_DIR OUT_DIR\n");
    return 2;
  }
  try {
    const std::string clip = argv[1], wdir = argv[2], out = argv[3];
    recordings::write_tracker_csv(out + "/session.csv", capi_test::device_session(clip), "C API test session from " + clip);
    const auto frames = recordings::read_tracker_csv(out + "/session.csv");
    {
      avatar::LoBSTrCompact p(avatar::LoBSTrCompact::load(wdir + "/lobstr_compact.weights.json"));
      run(p, frames, out + "/lobstr.ref");
    }
    const auto n3p = avatar::N3PDirect::load(wdir + "/n3p");
    {
      avatar::N3PDirect p(n3p);
      run(p, frames, out + "/n3p_direct.ref");
    }
    {
      avatar::N3PPhysicsDefaultSizes<float> p(n3p);
      run(p, frames, out + "/n3p_physics.ref");
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}

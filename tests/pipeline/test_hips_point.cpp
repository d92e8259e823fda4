// The pelvis tracker of trackers synthesised at the joints sits where the standard skeleton has its
// hips joint (pose::standard_hips_point), whatever joint a rig roots at: CMU's root is at the lower
// back, ~10 cm above and behind the hip centre. A rig proportioned like the standard keeps its own
// root bit for bit (the training clips). Python twin: weights_tool/tests/test_lobstr_pipeline.py
// (the same rig text).
#include <doctest/doctest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "sparsebody/pose/body_proportions.hpp"
#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

using namespace sparsebody;

namespace {

std::string joint(const char* name, double x, double y, double z, const std::string& inner) {
  std::ostringstream s;
  s << "JOINT " << name << "\n{\nOFFSET " << x << " " << y << " " << z << "\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
    << inner << "}\n";
  return s.str();
}

// A rig in centimetres (leg 40 + 40) whose thigh roots sit at (+-ux, uy, uz) from its root; two
// frames, the second moved by (10, 0, 5) cm and turned a quarter about Y.
std::string rig(double uy, double uz, double ux = 8.0) {
  const std::string end = "End Site\n{\nOFFSET 0 5 0\n}\n";
  auto leg = [&](bool left) {
    return joint(left ? "LeftUpLeg" : "RightUpLeg", left ? ux : -ux, uy, uz,
                 joint(left ? "LeftLeg" : "RightLeg", 0, -40, 0,
                       joint(left ? "LeftFoot" : "RightFoot", 0, -40, 0,
                             joint(left ? "LeftToeBase" : "RightToeBase", 0, -4, 10, end))));
  };
  std::ostringstream s;
  s << "HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    << joint("Spine", 0, 16, 0,
             joint("Head", 0, 40, 0, end) + joint("LeftHand", 20, 20, 0, end) + joint("RightHand", -20, 20, 0, end))
    << leg(true) << leg(false) << "}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n";
  const int channels = 6 + 3 * 12;
  for (int f = 0; f < 2; ++f)
    for (int c = 0; c < channels; ++c) {
      const double v = c == 0 ? 10.0 * f : c == 1 ? 100.0 : c == 2 ? 5.0 * f : c == 5 ? 90.0 * f : 0.0;  // c 5: root Y
      s << v << (c + 1 < channels ? " " : "\n");
    }
  return s.str();
}

recordings::BvhClip parse(const std::string& text) {
  std::istringstream in(text);
  return recordings::parse_bvh(in, "rig.bvh");
}

}  // namespace

TEST_CASE("pelvis tracker at the standard hips joint: a rig rooted at the lower back is moved there, a standard one is not") {
  const double leg = 80.0;
  const double above = pose::kStandardHipsAboveThighRoots * leg;  // 2.19 cm
  SUBCASE("CMU-like: the root 10 cm above and 5 cm behind the thigh roots' midpoint") {
    const recordings::BvhClip clip = parse(rig(-10.0, 5.0));
    const pose::JointMap m = pose::JointMap::from_names(clip.skeleton, "rig.bvh");
    const Eigen::Vector3d p = pose::standard_hips_point(clip.skeleton, m);
    CHECK(p.x() == doctest::Approx(0.0));
    CHECK(p.y() == doctest::Approx(-10.0 + above).epsilon(1e-12));
    CHECK(p.z() == doctest::Approx(5.0).epsilon(1e-12));
    // The torso is measured from there: hips point to head.
    const pose::BodyLengths b = pose::BodyLengths::of(clip.skeleton, m);
    CHECK(b.torso == doctest::Approx((Eigen::Vector3d(0, 56, 0) - p).norm()).epsilon(1e-12));
    // Synthesis: the pelvis tracker is the root plus R_root p, in metres, floor subtracted; frame 1
    // is turned a quarter about Y, so the hips-local (0, y, 5 cm) becomes world (5 cm, y, 0).
    const double units = recordings::guess_units(clip.skeleton, m);
    REQUIRE(units == 0.01);
    const recordings::SyntheticTrackers syn = recordings::synthesize_trackers(clip, m, units);
    const auto& f0 = syn.frames[0].pose[3].position;
    const auto& f1 = syn.frames[1].pose[3].position;
    CHECK(f0.x == doctest::Approx(0.0).epsilon(1e-6));
    CHECK(f0.y == doctest::Approx(1.0 + 0.01 * p.y() - syn.floor).epsilon(1e-6));
    CHECK(f0.z == doctest::Approx(0.05).epsilon(1e-6));
    CHECK(f1.x == doctest::Approx(0.10 + 0.05).epsilon(1e-6));
    CHECK(f1.y == doctest::Approx(1.0 + 0.01 * p.y() - syn.floor).epsilon(1e-6));
    CHECK(f1.z == doctest::Approx(0.05 + 0.0).epsilon(1e-6));
  }
  SUBCASE("standard proportions (Bandai Namco): the root is the hips joint, trackers unchanged") {
    const recordings::BvhClip clip = parse(rig(-above, 0.0));
    const pose::JointMap m = pose::JointMap::from_names(clip.skeleton, "rig.bvh");
    CHECK(pose::standard_hips_point(clip.skeleton, m) == Eigen::Vector3d::Zero());
    const recordings::SyntheticTrackers syn = recordings::synthesize_trackers(clip, m, 0.01);
    CHECK(syn.frames[1].pose[3].position.x == 0.10f);
    CHECK(syn.frames[1].pose[3].position.z == 0.05f);
    CHECK(pose::BodyLengths::of(clip.skeleton, m).torso == 56.0);
  }
  SUBCASE("within 0.6 % of the leg (0.48 cm here) a rig keeps its root; beyond, it does not") {
    const recordings::BvhClip near = parse(rig(-above + 0.4, 0.0));
    const recordings::BvhClip far = parse(rig(-above + 0.6, 0.0));
    const pose::JointMap m = pose::JointMap::from_names(near.skeleton, "rig.bvh");
    CHECK(pose::standard_hips_point(near.skeleton, m) == Eigen::Vector3d::Zero());
    CHECK(pose::standard_hips_point(far.skeleton, m).y() == doctest::Approx(0.6).epsilon(1e-4));  // the text keeps 6 digits
  }
  SUBCASE("a degenerate rig (both thigh roots at one point: no left axis) still gets a finite point") {
    // Only the pelvis's up axis (towards the spine) places the point, so the answer is the CMU-like one.
    const recordings::BvhClip clip = parse(rig(-10.0, 5.0, 0.0));
    const pose::JointMap m = pose::JointMap::from_names(clip.skeleton, "rig.bvh");
    const Eigen::Vector3d p = pose::standard_hips_point(clip.skeleton, m);
    REQUIRE(p.allFinite());
    CHECK(p.y() == doctest::Approx(-10.0 + above).epsilon(1e-12));
    CHECK(p.z() == doctest::Approx(5.0).epsilon(1e-12));
    CHECK(std::isfinite(pose::BodyLengths::of(clip.skeleton, m).torso));
  }
}

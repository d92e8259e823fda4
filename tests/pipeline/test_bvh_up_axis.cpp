// A BVH clip whose world is not Y-up (recordings/bvh_up_axis.hpp): the CMU clip 01_01 turned so its
// up is +Z, -Z, +X or -Y reads back as the original (world positions, synthesised trackers), and the
// original is left as it is.
#include <doctest/doctest.h>

#include <Eigen/Geometry>

#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/bvh_up_axis.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

using namespace sparsebody;

namespace {

const char* kClip = "/usr/share/assimp/models/BVH/01_01.bvh";  // assimp-testmodels (installed by .ci)

// The clip with its world turned by T: root position T p, root rotation T R (channels Z Y X).
recordings::BvhClip turned(recordings::BvhClip c, const Eigen::Matrix3d& T) {
  REQUIRE(c.channels[0].size() == 6);
  REQUIRE(c.channels[0][3] == recordings::BvhChannel::Zrotation);
  REQUIRE(c.channels[0][4] == recordings::BvhChannel::Yrotation);
  REQUIRE(c.channels[0][5] == recordings::BvhChannel::Xrotation);
  for (int f = 0; f < c.frames; ++f) {
    double* v = c.motion.data() + static_cast<std::size_t>(f) * c.channel_count;
    const Eigen::Vector3d p = T * Eigen::Vector3d(v[0], v[1], v[2]);
    const double d = M_PI / 180.0;
    const Eigen::Matrix3d R = T * (Eigen::AngleAxisd(v[3] * d, Eigen::Vector3d::UnitZ()) *
                                   Eigen::AngleAxisd(v[4] * d, Eigen::Vector3d::UnitY()) *
                                   Eigen::AngleAxisd(v[5] * d, Eigen::Vector3d::UnitX())).toRotationMatrix();
    const Eigen::Vector3d zyx = R.eulerAngles(2, 1, 0);  // R = Rz Ry Rx
    for (int k = 0; k < 3; ++k) v[k] = p(k), v[3 + k] = zyx(k) / d;
  }
  return c;
}

}  // namespace

TEST_CASE("BVH up axis: a Z-up (or X-up, upside-down) clip is turned to +Y and reads as the Y-up original") {
  const recordings::BvhClip original = recordings::read_bvh(kClip);
  const pose::JointMap map = pose::JointMap::from_names(original.skeleton, kClip);
  recordings::BvhClip plain = original;
  const recordings::UpAxis same = recordings::make_y_up(plain, map);
  CHECK_FALSE(same.turned);
  CHECK(same.axis == 1);
  CHECK(same.share > 0.9);
  const double units = recordings::guess_units(original.skeleton, map);
  const recordings::SyntheticTrackers want = recordings::synthesize_trackers(original, map, units);
  struct Case {
    const char* name;
    Eigen::Matrix3d T;  // the file's world = T (Y-up world)
    int axis, sign;
  };
  const Case cases[] = {
      {"+Z up", Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix(), 2, 1},
      {"-Z up", Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix(), 2, -1},
      {"+X up", Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 0, 1},
      {"upside down", Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix(), 1, -1}};
  for (const Case& c : cases) {
    CAPTURE(c.name);
    recordings::BvhClip z = turned(original, c.T);
    const recordings::UpAxis up = recordings::make_y_up(z, map);
    REQUIRE(up.turned);
    CHECK(up.axis == c.axis);
    CHECK(up.sign == c.sign);
    CHECK(up.share > 0.9);
    // world poses as the original's: the turn undoes T
    pose::BodyPose a, b;
    a.resize(original.skeleton.size());
    b.resize(original.skeleton.size());
    pose::Vec3Vector ta(static_cast<std::size_t>(original.skeleton.size())), tb = ta;
    pose::WorldPose wa, wb;
    wa.resize(original.skeleton.size());
    wb.resize(original.skeleton.size());
    double worst = 0;
    for (int f = 0; f < original.frames; f += 97) {
      original.world_pose(f, a, ta, wa, units);
      z.world_pose(f, b, tb, wb, units);
      for (int j = 0; j < original.skeleton.size(); ++j) worst = std::max(worst, (wa.position[j] - wb.position[j]).norm());
    }
    CHECK(worst < 1e-9);
    // and so are the trackers synthesised from it (floor included)
    const recordings::SyntheticTrackers got = recordings::synthesize_trackers(z, map, units);
    REQUIRE(got.frames.size() == want.frames.size());
    CHECK(got.floor == doctest::Approx(want.floor).epsilon(1e-9));
    double tracker_worst = 0;
    for (std::size_t f = 0; f < want.frames.size(); f += 31)
      for (int k = 0; k < trackers::kTrackerCount; ++k)
        tracker_worst = std::max(tracker_worst, (trackers::to_eigen(got.frames[f].pose[k].position) -
                                                 trackers::to_eigen(want.frames[f].pose[k].position)).norm());
    CHECK(tracker_worst < 1e-5);  // float positions
    // a second look gives the same turn (make_y_up starts from the file's world)
    recordings::BvhClip again = z;
    recordings::make_y_up(again, map);
    CHECK(again.world_turn.coeffs().isApprox(z.world_turn.coeffs()));
  }
}

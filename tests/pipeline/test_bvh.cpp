// BVH reader/writer: channel orders and counts, units, round trip, malformed input with line numbers.
#include <doctest/doctest.h>

#include <sstream>

#include "sparsebody/recordings/bvh.hpp"

using namespace sparsebody;

namespace {
const char* kClip = R"(HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    End Site
    {
      OFFSET 0 5 0
    }
  }
  JOINT Leg
  {
    OFFSET 5 0 0
    CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
    JOINT Foot
    {
      OFFSET 0 -40 0
      CHANNELS 1 Yrotation
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.0083333
1 90 2 0 0 0 90 0 0 5 0 0 0 0 0 0
0 90 0 0 90 0 0 0 0 5 0 0 0 0 0 45
)";

recordings::BvhClip parse(const std::string& s) {
  std::istringstream in(s);
  return recordings::parse_bvh(in, "clip.bvh");
}

std::string error_of(const std::string& s) {
  try {
    parse(s);
  } catch (const LoadError& e) {
    return e.what();
  }
  return "";
}

std::string replace(std::string s, const std::string& a, const std::string& b) {
  const auto p = s.find(a);
  REQUIRE(p != std::string::npos);
  return s.replace(p, a.size(), b);
}
}  // namespace

TEST_CASE("BVH reader: hierarchy, channel orders and counts, forward kinematics") {
  const recordings::BvhClip c = parse(kClip);
  REQUIRE(c.skeleton.size() == 4);
  CHECK(c.skeleton.names[3] == "Foot");
  CHECK(c.skeleton.parents[3] == 2);
  CHECK(c.skeleton.parents[2] == 0);
  CHECK(c.channel_count == 16);
  CHECK(c.frames == 2);
  CHECK(c.frame_time == doctest::Approx(0.0083333));
  CHECK(c.end_site[1] == 1);
  CHECK(c.end_offset[1].y() == doctest::Approx(5));
  pose::BodyPose tmp;
  tmp.resize(4);
  pose::Vec3Vector tr(4);
  pose::WorldPose w;
  w.resize(4);
  c.world_pose(0, tmp, tr, w);
  // frame 0: root at (1, 90, 2); Spine rotated 90 deg about X does not move the spine joint itself
  CHECK(w.position[0].isApprox(Eigen::Vector3d(1, 90, 2)));
  CHECK(w.position[1].isApprox(Eigen::Vector3d(1, 100, 2)));
  CHECK(w.position[2].isApprox(Eigen::Vector3d(6, 90, 2)));  // 6-channel joint: position channels replace the offset
  CHECK(w.position[3].isApprox(Eigen::Vector3d(6, 50, 2)));
  // frame 1: root rotated 90 deg about Y (its Zrotation Yrotation Xrotation = 0 90 0): the leg's
  // position channels (5, 0, 0) -> (0, 0, -5); the spine offset along Y is unchanged
  c.world_pose(1, tmp, tr, w);
  CHECK((w.position[1] - Eigen::Vector3d(0, 100, 0)).norm() < 1e-9);
  CHECK((w.position[2] - Eigen::Vector3d(0, 90, -5)).norm() < 1e-9);
  CHECK((w.position[3] - Eigen::Vector3d(0, 50, -5)).norm() < 1e-9);
}

TEST_CASE("BVH writer output reads back with the same world positions (Z X Y Euler round trip)") {
  const recordings::BvhClip c = parse(kClip);
  pose::BodyPose p;
  p.resize(4);
  pose::Vec3Vector tr(4);
  pose::WorldPose w0, w1;
  w0.resize(4);
  w1.resize(4);
  recordings::BvhWriter writer(c.skeleton, c.frame_time);
  for (int f = 0; f < c.frames; ++f) {
    c.local_pose(f, p, tr);
    p.local[1] = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())) * p.local[1];
    writer.add(p);
  }
  std::ostringstream out;
  writer.write(out);
  const recordings::BvhClip back = parse(out.str());
  REQUIRE(back.skeleton.size() == 4);
  CHECK(back.frames == 2);
  for (int f = 0; f < c.frames; ++f) {
    c.local_pose(f, p, tr);
    p.local[1] = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())) * p.local[1];
    pose::forward_kinematics(c.skeleton, p, w0);
    // the writer drops the non-root position channels: compare with offsets as the skeleton has them
    pose::BodyPose q;
    q.resize(4);
    pose::Vec3Vector tq(4);
    back.world_pose(f, q, tq, w1);
    for (int j = 0; j < 4; ++j) {
      CHECK((w0.rotation[j].toRotationMatrix() - w1.rotation[j].toRotationMatrix()).norm() < 1e-4);
      CHECK((w0.position[j] - w1.position[j]).norm() < 1e-3);
    }
  }
}

TEST_CASE("Z X Y Euler decomposition recovers the rotation") {
  for (int i = 0; i < 50; ++i) {
    const Eigen::Quaterniond q = Eigen::Quaterniond::UnitRandom();
    const Eigen::Vector3d e = recordings::euler_zxy_degrees(q.toRotationMatrix()) * (M_PI / 180);
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(e.x(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(e.y(), Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(e.z(), Eigen::Vector3d::UnitY())).toRotationMatrix();
    CHECK((R - q.toRotationMatrix()).norm() < 1e-9);
  }
}

TEST_CASE("malformed BVH: LoadError names the file, the line and what was expected") {
  CHECK(error_of(replace(kClip, "OFFSET 0 10 0", "OFFSET 0 ten 0")) == "clip.bvh: line 8: expected OFFSET x y z (3 numbers), got 'ten'");
  CHECK(error_of(replace(kClip, "CHANNELS 1 Yrotation", "CHANNELS 1 Yrot")).find("line 22: expected a channel name") != std::string::npos);
  CHECK(error_of(replace(kClip, "CHANNELS 1 Yrotation", "CHANNELS 2 Yrotation")).find("line 22: expected a channel name") != std::string::npos);
  CHECK(error_of(replace(kClip, "Frames: 2", "Frames: 3")).find("expected 3 frames, found 2") != std::string::npos);
  CHECK(error_of(replace(kClip, "0 90 0 0 90 0 0 0 0 5 0 0 0 0 0 45", "0 90 0 0 90 0 0 0 0 5 0 0 0 0 0")).find("line 30: expected frame 1: 16 numbers") != std::string::npos);
  CHECK(error_of(replace(kClip, "0 90 0 0 90 0 0 0 0 5 0 0 0 0 0 45", "0 90 0 0 90 0 0 0 0 5 0 0 0 0 0 45 7")).find("line 30: frame 1: more than 16 numbers") != std::string::npos);
  CHECK(error_of(replace(kClip, "Frame Time: 0.0083333", "Frame Time: 0")).find("line 28: expected a positive frame time") != std::string::npos);
  CHECK(error_of(replace(kClip, "  JOINT Leg", "  JIONT Leg")).find("line 15: expected ROOT, JOINT") != std::string::npos);
  CHECK(error_of(std::string(kClip).substr(0, 200)).find("unexpected end of file inside HIERARCHY") != std::string::npos);
  CHECK(error_of("").find("line 0: expected HIERARCHY") != std::string::npos);
  CHECK_THROWS_AS(recordings::read_bvh("/nonexistent/x.bvh"), LoadError);
}

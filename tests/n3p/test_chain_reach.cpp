// pose::ChainReach (the spine bending the head joint onto the headset in direct mode): checked
// against forward kinematics, which it does not use: the head reaches a reachable target, keeps its
// world rotation, the hips and everything below the chain stay, each joint turns at most
// passes x max_angle, and a NaN target changes nothing.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>

#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/chain_reach.hpp"

using namespace sparsebody;

namespace {
// hips -> spine -> chest -> neck -> head, an arm off the chest, a leg off the hips
pose::Skeleton spine_skeleton() {
  pose::Skeleton s;
  s.names = {"Hips", "Spine", "Chest", "Neck", "Head", "Shoulder", "Hand", "UpLeg", "Foot"};
  s.parents = {-1, 0, 1, 2, 3, 2, 5, 0, 7};
  s.offsets = {Eigen::Vector3d::Zero(), {0, 0.12, 0.01}, {0, 0.2, -0.01}, {0, 0.22, 0.02}, {0, 0.1, 0.0},
               {0.18, 0.15, 0}, {0.5, 0, 0}, {0.09, -0.05, 0}, {0, -0.85, 0}};
  return s;
}

pose::BodyPose random_pose(const pose::Skeleton& s, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 0.15);
  pose::BodyPose p;
  p.resize(s.size());
  p.root_position = Eigen::Vector3d(0.3, 0.95, -0.2);
  for (auto& q : p.local) q = Eigen::Quaterniond(Eigen::AngleAxisd(n(rng), Eigen::Vector3d::UnitX()) *
                                               Eigen::AngleAxisd(n(rng), Eigen::Vector3d::UnitY()) *
                                               Eigen::AngleAxisd(n(rng), Eigen::Vector3d::UnitZ()));
  return p;
}
}  // namespace

TEST_CASE("chain reach: the head joint reaches a reachable target; the head's rotation and the rest stay") {
  const pose::Skeleton s = spine_skeleton();
  const int head = s.find("Head");
  const pose::ChainReach reach(s, head, 3);
  REQUIRE(reach.size() == 3);  // neck, chest, spine: not the hips
  std::mt19937 rng(7);
  std::normal_distribution<double> turn(0.0, 0.06);  // rad: the chain's joints turned ~3.4 deg each
  double worst = 0, moved = 0;
  for (int trial = 0; trial < 200; ++trial) {
    pose::BodyPose p = random_pose(s, rng);
    pose::WorldPose w0, w, fk;
    w0.resize(s.size()), w.resize(s.size()), fk.resize(s.size());
    pose::forward_kinematics(s, p, w0);
    w = w0;
    // a target the chain can reach: the head of the same pose with the spine, chest and neck turned
    pose::BodyPose bent = p;
    for (const char* j : {"Spine", "Chest", "Neck"}) {
      const Eigen::Vector3d axis = Eigen::Vector3d(turn(rng), turn(rng), turn(rng));
      bent.local[s.find(j)] = Eigen::Quaterniond(Eigen::AngleAxisd(axis.norm(), axis.normalized())) * bent.local[s.find(j)];
    }
    pose::forward_kinematics(s, bent, fk);
    const Eigen::Vector3d target = fk.position[head];
    moved = std::max(moved, (target - w0.position[head]).norm());
    const double before = (w0.position[head] - target).norm();
    const double left = reach.solve(s, p, w, target);
    pose::forward_kinematics(s, p, fk);  // the oracle: the new locals, composed from scratch
    const double after = (fk.position[head] - target).norm();
    CHECK(after == doctest::Approx(left).epsilon(1e-9).scale(1e-9));  // its own world poses agree with FK
    CHECK(after <= before + 1e-12);
    worst = std::max(worst, after);
    CHECK(fk.rotation[head].angularDistance(w0.rotation[head]) < 1e-9);  // the head looks where it looked
    for (const char* j : {"Hips", "Spine", "UpLeg", "Foot"}) {  // below the chain: unchanged
      const int k = s.find(j);
      CHECK((fk.position[k] - w0.position[k]).norm() < 1e-12);
    }
    CHECK(fk.position[s.find("Hand")].allFinite());
  }
  MESSAGE("worst remaining distance: " << worst << " m, for targets up to " << moved << " m away");
  CHECK(moved > 0.05);
  CHECK(worst < 0.01);  // 3 passes: CCD converges geometrically, not exactly
}

TEST_CASE("chain reach: an unreachable target gets closer, each joint turns a bounded angle; NaN changes nothing") {
  const pose::Skeleton s = spine_skeleton();
  const int head = s.find("Head");
  const pose::ChainReach reach(s, head, 3);
  std::mt19937 rng(3);
  pose::BodyPose p = random_pose(s, rng);
  const pose::BodyPose p0 = p;
  pose::WorldPose w;
  w.resize(s.size());
  pose::forward_kinematics(s, p, w);
  const pose::ChainReachConfig cfg;
  const Eigen::Vector3d far = w.position[head] + Eigen::Vector3d(1.5, -1.0, 0.5);
  const double before = (w.position[head] - far).norm();
  const double after = reach.solve(s, p, w, far, cfg);
  CHECK(after < before);
  // the base's turn is its own passes only (the hips stay): at most passes x max_angle
  const int base = s.find("Spine");
  CHECK(p.local[base].angularDistance(p0.local[base]) <= cfg.passes * cfg.max_angle + 1e-9);
  CHECK(p.local[base].angularDistance(p0.local[base]) > 0.5 * cfg.passes * cfg.max_angle);  // it did turn
  pose::BodyPose q = p0;
  pose::WorldPose wq;
  wq.resize(s.size());
  pose::forward_kinematics(s, q, wq);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK(std::isnan(reach.solve(s, q, wq, Eigen::Vector3d(nan, 0, 0))));
  for (int j = 0; j < s.size(); ++j) CHECK(q.local[j].coeffs() == p0.local[j].coeffs());
  // no chain (the root itself): nothing to bend
  CHECK(pose::ChainReach(s, 0, 3).empty());
  CHECK(pose::ChainReach(s, -1, 3).empty());
}

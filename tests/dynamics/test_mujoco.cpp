// Cross-check against MuJoCo 2.2.2 on the exported MJCF (gravity on, contacts off).
// Frame conversions: MuJoCo's free joint has qvel = (linear velocity in world, angular in local),
// ours (angular, linear) both in the body frame, so for the root
//   qvel_mj = (R v_b, w_b),  qacc_mj = (R (dv_b + w_b x v_b), dw_b),  qfrc_mj = (R f_b, n_b).
#include <doctest/doctest.h>
#include <mujoco/mujoco.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/character/humanoid3d.hpp"
#include "sparsebody/dynamics/aba.hpp"
#include "sparsebody/dynamics/mjcf.hpp"
#include "sparsebody/dynamics/rnea.hpp"
#include "test_util.hpp"

using namespace sparsebody;
using namespace sparsebody::dynamics;

template <class Model>
static mjModel* load_export(const Model& m, const MjcfOptions& o, const std::string& tag) {
  const std::string path = std::string(SPARSEBODY_BINARY_DIR) + "/dyn_" + tag + ".xml";
  std::ofstream(path) << to_mjcf(m, o);
  char err[1000] = "";
  mjModel* mm = mj_loadXML(path.c_str(), nullptr, err, sizeof err);
  if (!mm) std::printf("MuJoCo load error: %s\n", err);
  return mm;
}

// MuJoCo numbers DoFs in depth-first body order; ours follow the model's body order. Joints are
// matched by name (the exporter names each joint after its body).
static std::vector<int> g_qperm, g_vperm;
template <class Model>
static void build_perm(const Model& m, const mjModel* mm) {
  g_qperm.assign(m.nq, -1);
  g_vperm.assign(m.nv, -1);
  for (int i = 0; i < m.nb; ++i) {
    const auto& b = m.bodies[i];
    if (joint_nv(b.joint) == 0) continue;
    const int j = mj_name2id(mm, mjOBJ_JOINT, m.names[i].c_str());
    REQUIRE(j >= 0);
    for (int k = 0; k < joint_nq(b.joint); ++k) g_qperm[b.q_index + k] = mm->jnt_qposadr[j] + k;
    for (int k = 0; k < joint_nv(b.joint); ++k) g_vperm[b.v_index + k] = mm->jnt_dofadr[j] + k;
  }
}

// Our generalized vector (velocity/acceleration/force layout) to MuJoCo's, given root rotation R.
template <class Model, class Vec>
static void to_mj(const Model& m, const Mat3<double>& R, const Vec& x, double* out, const Vec3<double>* accel_w = nullptr,
                 const Vec3<double>* accel_v = nullptr, bool force = false) {
  for (int k = 0; k < m.nv; ++k) out[g_vperm[k]] = x(k);
  if (m.root_body() == 0) {  // a free root's DoFs are 0..5 in both
    const Vec3<double> ang = x.template head<3>(), lin = x.template segment<3>(3);
    Vec3<double> l = lin;
    if (accel_w && !force) l = lin + accel_w->cross(*accel_v);
    const Vec3<double> lw = R * l;
    for (int k = 0; k < 3; ++k) { out[k] = lw(k); out[3 + k] = ang(k); }
  }
}

template <class Model>
static void cross_check(const Model& m, const char* tag, unsigned seed) {
  MjcfOptions o;
  o.contact = false;
  mjModel* mm = load_export(m, o, tag);
  REQUIRE(mm != nullptr);
  o.servo_damping = true;
  mjModel* mmd = load_export(m, o, std::string(tag) + "_damped");
  REQUIRE(mmd != nullptr);
  REQUIRE(mm->nv == m.nv);
  REQUIRE(mm->nq == m.nq);
  build_perm(m, mm);
  mjData* md = mj_makeData(mm);
  mjData* mdd = mj_makeData(mmd);
  Data<double, Model::kMaxBodies, Model::kMaxDofs> d(m);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n;
  typename Model::VecQ q;
  typename Model::VecV qd, tau, qdd, tau_id;
  std::vector<double> buf(m.nv), rne(m.nv);
  double worst_acc = 0, worst_id = 0, worst_imp = 0;
  const double h = o.timestep;
  for (int t = 0; t < 300; ++t) {
    dyn_test::random_state(m, rng, q, qd);
    tau.resize(m.nv);
    for (int k = 0; k < m.nv; ++k) tau(k) = 10 * n(rng);
    // --- forward dynamics, no damping
    REQUIRE(dyn_test::aba_damped(m, d, q, qd, tau, qdd, 0.0));
    forward_kinematics(m, d, q, &qd);
    const Mat3<double> R = d.R[0];
    const Vec3<double> w0 = qd.template head<3>(), v0 = qd.template segment<3>(3);
    for (int k = 0; k < m.nq; ++k) md->qpos[g_qperm[k]] = q(k);
    to_mj(m, R, qd, md->qvel);
    to_mj(m, R, tau, md->qfrc_applied, nullptr, nullptr, true);
    mj_forward(mm, md);
    to_mj(m, R, qdd, buf.data(), &w0, &v0);
    double num = 0, den = 0;
    for (int k = 0; k < m.nv; ++k) { num += (buf[k] - md->qacc[k]) * (buf[k] - md->qacc[k]); den += md->qacc[k] * md->qacc[k]; }
    worst_acc = std::max(worst_acc, std::sqrt(num / den));
    // --- inverse dynamics: mj_rne(qacc) vs RNEA(qdd), with a random qdd
    typename Model::VecV a(m.nv);
    for (int k = 0; k < m.nv; ++k) a(k) = 5 * n(rng);
    rnea(m, d, q, qd, a, tau_id);
    to_mj(m, R, a, md->qacc, &w0, &v0);
    mj_rne(mm, md, 1, rne.data());
    // mj_rne uses the bodies' inertias only; MuJoCo's M (and mj_inverse) adds armature * qacc.
    for (int k = 0; k < m.nv; ++k) rne[k] += mm->dof_armature[k] * md->qacc[k];
    to_mj(m, R, tau_id, buf.data(), nullptr, nullptr, true);
    num = den = 0;
    for (int k = 0; k < m.nv; ++k) { num += (buf[k] - rne[k]) * (buf[k] - rne[k]); den += rne[k] * rne[k]; }
    worst_id = std::max(worst_id, std::sqrt(num / den));
    // --- implicit damping: MuJoCo's Euler solves (M + h D) qacc = f; compare the velocity update
    typename Model::VecV tau_pd = tau;
    for (int i = 0; i < m.nb; ++i) {
      const auto& b = m.bodies[i];
      for (int k = 0; k < joint_nv(b.joint); ++k) tau_pd(b.v_index + k) -= (b.kd + b.damping) * qd(b.v_index + k);
    }
    REQUIRE(dyn_test::aba_damped(m, d, q, qd, tau_pd, qdd, h));
    for (int k = 0; k < m.nq; ++k) mdd->qpos[g_qperm[k]] = q(k);
    to_mj(m, R, qd, mdd->qvel);
    to_mj(m, R, tau, mdd->qfrc_applied, nullptr, nullptr, true);
    std::vector<double> qvel0(mdd->qvel, mdd->qvel + m.nv);
    mj_step(mmd, mdd);
    to_mj(m, R, qdd, buf.data(), &w0, &v0);
    num = den = 0;
    for (int k = 0; k < m.nv; ++k) {
      const double acc = (mdd->qvel[k] - qvel0[k]) / h;
      num += (buf[k] - acc) * (buf[k] - acc);
      den += acc * acc;
    }
    worst_imp = std::max(worst_imp, std::sqrt(num / den));
  }
  std::printf("[mujoco] %s: qacc max rel err %.2e, inverse dynamics (mj_rne) %.2e, implicit-damping Euler %.2e\n",
              tag, worst_acc, worst_id, worst_imp);
  CHECK(worst_acc <= 1e-8);
  CHECK(worst_id <= 1e-8);
  CHECK(worst_imp <= 1e-8);  // (qvel_after - qvel_before) / h of one mj_step
  mj_deleteData(md);
  mj_deleteData(mdd);
  mj_deleteModel(mm);
  mj_deleteModel(mmd);
}

TEST_CASE("MuJoCo 2.2.2 agrees on the 34-DoF humanoid3d-like tree") {
  cross_check(character::humanoid3d_like<double>(), "humanoid34", 11);
}
TEST_CASE("MuJoCo 2.2.2 agrees on the default avatar") {
  cross_check(character::default_avatar<double>(), "avatar", 12);
}
TEST_CASE("MuJoCo 2.2.2 agrees on the default avatar with joint armature") {
  auto m = character::default_avatar<double>();
  for (int i = 1; i < m.nb; ++i) m.bodies[i].armature = 0.01 + 0.01 * (i % 7);  // exported as MuJoCo's armature
  m.finalize();
  cross_check(m, "avatar_armature", 13);
}

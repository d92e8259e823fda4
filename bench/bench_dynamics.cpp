// Dynamics benchmarks: ABA, RNEA, CRBA and a full step (PD + contacts) on the 34-DoF
// humanoid3d-like tree and on the default avatar, against MuJoCo 2.2.2 (mj_step, mj_forward,
// mj_rne, mj_crb) on the same exported MJCF and, when built with it (bench/dynamics.cmake),
// RBDL 3.3.1 (ForwardDynamics, InverseDynamics, CompositeRigidBodyAlgorithm) on the identical
// 34-DoF tree. Each MuJoCo benchmark also reports `ratio` = MuJoCo time / ours timed back to back
// (median of 5 chrono batches); the end of the run prints the same-run ratios peer / ours of the
// benchmarks' medians, real and CPU time (registered with bench/ratio_report.hpp's add_ratio).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/character/humanoid3d.hpp"
#include "sparsebody/dynamics/aba.hpp"
#include "sparsebody/dynamics/crba.hpp"
#include "sparsebody/dynamics/mjcf.hpp"
#include "sparsebody/dynamics/pd_servo.hpp"
#include "sparsebody/dynamics/rnea.hpp"
#include "sparsebody/dynamics/simulator.hpp"
#include "ratio_report.hpp"
#ifdef SPARSEBODY_HAVE_MUJOCO
#include <mujoco/mujoco.h>
#endif
#ifdef SPARSEBODY_HAVE_RBDL
#include <rbdl/rbdl.h>
#endif

using namespace sparsebody;
using namespace sparsebody::dynamics;

namespace {

using H34 = Model<double, 16, 40>;
using Av = Model<double, 24, 72>;

template <class M>
struct Fixture {
  M m;
  Data<double, M::kMaxBodies, M::kMaxDofs> d;
  typename M::VecQ q;
  typename M::VecV qd, tau, qdd;
  explicit Fixture(const M& model) : m(model), d(model) {
    std::mt19937 rng(1);
    std::normal_distribution<double> n;
    q = m.neutral_configuration();
    for (int i = 0; i < m.nb; ++i) {  // a moderately bent pose
      const auto& b = m.bodies[i];
      if (b.joint == JointType::Spherical) {
        const Quat<double> r = quat_exp(Vec3<double>(0.3 * n(rng), 0.3 * n(rng), 0.3 * n(rng)));
        q(b.q_index) = r.w(); q(b.q_index + 1) = r.x(); q(b.q_index + 2) = r.y(); q(b.q_index + 3) = r.z();
      } else if (b.joint == JointType::Revolute) {
        q(b.q_index) = 0.3 * n(rng);
      }
    }
    qd.resize(m.nv);
    tau.resize(m.nv);
    for (int k = 0; k < m.nv; ++k) { qd(k) = n(rng); tau(k) = 10 * n(rng); }
    qdd.setZero(m.nv);
    implicit_damping_diagonal(m, 1.0 / 120, true, d.implicit_diagonal);  // ABA with the servos' h Kd
  }
};

// Model standing on its feet (root lowered so the foot boxes touch the floor).
template <class M>
typename M::VecQ standing(const M& m) {
  typename M::VecQ q = m.neutral_configuration();
  Data<double, M::kMaxBodies, M::kMaxDofs> d(m);
  forward_kinematics(m, d, q, nullptr);
  double lo = 1e9;
  for (int k = 0; k < m.num_points; ++k)
    lo = std::min(lo, point_position(d, m.points[k].body, m.points[k].pos).y() - m.points[k].radius);
  q(1) -= lo + 0.0005;  // 0.5 mm into the floor
  return q;
}

const H34& h34() { static H34 m = character::humanoid3d_like<double>(); return m; }
const Av& avatar() { static Av m = character::default_avatar<double>(); return m; }

// Per-call time of f in microseconds: median of 5 batches.
template <class F>
double time_us(F&& f, int iters) {
  std::array<double, 5> t{};
  for (double& x : t) {
    const auto a = std::chrono::steady_clock::now();
    for (int i = 0; i < iters; ++i) f();
    x = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count() / iters;
  }
  std::sort(t.begin(), t.end());
  return t[2];
}

template <class M>
void run_aba(benchmark::State& st, const M& model) {
  Fixture<M> f(model);
  for (auto _ : st) {
    aba(f.m, f.d, f.q, f.qd, f.tau, f.qdd);
    benchmark::DoNotOptimize(f.qdd.data());
  }
}
template <class M>
void run_rnea(benchmark::State& st, const M& model) {
  Fixture<M> f(model);
  typename M::VecV out(f.m.nv);
  for (auto _ : st) {
    rnea(f.m, f.d, f.q, f.qd, f.tau, out);
    benchmark::DoNotOptimize(out.data());
  }
}
template <class M>
void run_crba(benchmark::State& st, const M& model) {
  Fixture<M> f(model);
  CrbaData<double, M::kMaxBodies, M::kMaxDofs> out(f.m);
  for (auto _ : st) {
    crba(f.m, f.d, f.q, out);
    benchmark::DoNotOptimize(out.M.data());
  }
}

// Full step at 120 Hz: PD servos (kp=200, kd=20, implicit) + contacts, standing; the state is
// reset every 60 steps so the feet stay on the ground.
template <class M>
struct StepRunner {
  Simulator<double, M::kMaxBodies, M::kMaxDofs> sim;
  typename M::VecQ q0;
  typename M::VecV v0;
  int k = 0;
  long contacts = 0, steps = 0;
  explicit StepRunner(const M& m) : sim(m), q0(standing(m)), v0(M::VecV::Zero(m.nv)) { sim.set_state(q0, v0); }
  void operator()() {
    if (++k == 60) { k = 0; sim.set_state(q0, v0); }
    benchmark::DoNotOptimize(sim.step(1.0 / 120));
    contacts += sim.num_active_contacts();
    ++steps;
  }
};
template <class M>
void run_step(benchmark::State& st, const M& model) {
  StepRunner<M> r(model);
  for (auto _ : st) r();
  st.counters["contacts"] = double(r.contacts) / double(std::max(1L, r.steps));
}

// ABA timed by a chrono loop inside the benchmark: 200 batches of 200 calls, reporting the
// 10th percentile and the median per call (wall, us). On a shared, loaded machine the low
// percentile is the better estimate of the unloaded cost than the mean of one long run.
template <class M>
void run_aba_loop(benchmark::State& st, const M& model) {
  Fixture<M> f(model);
  std::array<double, 200> t{};
  for (auto _ : st) {
    for (double& x : t) {
      const auto a = std::chrono::steady_clock::now();
      for (int i = 0; i < 200; ++i) {
        aba(f.m, f.d, f.q, f.qd, f.tau, f.qdd);
        benchmark::DoNotOptimize(f.qdd.data());
      }
      x = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count() / 200;
    }
  }
  std::sort(t.begin(), t.end());
  st.counters["p10_us"] = t[20];
  st.counters["median_us"] = t[100];
}
void BM_ABALoop_Humanoid34(benchmark::State& st) { run_aba_loop(st, h34()); }
void BM_ABALoop_Avatar(benchmark::State& st) { run_aba_loop(st, avatar()); }
BENCHMARK(BM_ABALoop_Humanoid34)->Iterations(1);
BENCHMARK(BM_ABALoop_Avatar)->Iterations(1);

void BM_ABA_Humanoid34(benchmark::State& st) { run_aba(st, h34()); }
void BM_RNEA_Humanoid34(benchmark::State& st) { run_rnea(st, h34()); }
void BM_CRBA_Humanoid34(benchmark::State& st) { run_crba(st, h34()); }
void BM_Step_Humanoid34(benchmark::State& st) { run_step(st, h34()); }
void BM_ABA_Avatar(benchmark::State& st) { run_aba(st, avatar()); }
void BM_RNEA_Avatar(benchmark::State& st) { run_rnea(st, avatar()); }
void BM_CRBA_Avatar(benchmark::State& st) { run_crba(st, avatar()); }
void BM_Step_Avatar(benchmark::State& st) { run_step(st, avatar()); }
// ABA with pass 2 one body at a time (Model::plan_backward_steps(false)): what the paired steps save.
template <class M>
M one_body_steps(const M& m) {
  M o = m;
  o.plan_backward_steps(false);
  return o;
}
void BM_ABAOneBodySteps_Humanoid34(benchmark::State& st) { run_aba(st, one_body_steps(h34())); }
void BM_ABAOneBodySteps_Avatar(benchmark::State& st) { run_aba(st, one_body_steps(avatar())); }
BENCHMARK(BM_ABA_Humanoid34);
BENCHMARK(BM_ABAOneBodySteps_Humanoid34);
BENCHMARK(BM_RNEA_Humanoid34);
BENCHMARK(BM_CRBA_Humanoid34);
BENCHMARK(BM_Step_Humanoid34);
BENCHMARK(BM_ABA_Avatar);
BENCHMARK(BM_ABAOneBodySteps_Avatar);
BENCHMARK(BM_RNEA_Avatar);
BENCHMARK(BM_CRBA_Avatar);
BENCHMARK(BM_Step_Avatar);

void BM_StepFloat_Humanoid34(benchmark::State& st) {
  const auto mf = h34().cast<float>();
  Simulator<float, 16, 40> sim(mf);
  const auto q0 = standing(h34());
  Model<float, 16, 40>::VecQ qf = q0.cast<float>();
  Model<float, 16, 40>::VecV vf = Model<float, 16, 40>::VecV::Zero(mf.nv);
  sim.set_state(qf, vf);
  int k = 0;
  for (auto _ : st) {
    if (++k == 60) { k = 0; sim.set_state(qf, vf); }
    benchmark::DoNotOptimize(sim.step(1.0f / 120));
  }
}
BENCHMARK(BM_StepFloat_Humanoid34);

#ifdef SPARSEBODY_HAVE_MUJOCO
// MuJoCo on the exported MJCF. contact=false for mj_forward / mj_rne (the ABA / RNEA analogues).
template <class M>
struct Mj {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  std::vector<double> qpos0;
  Mj(const M& model, bool contact, const std::string& tag) {
    MjcfOptions o;
    o.contact = contact;
    o.servo_damping = true;  // kd as MuJoCo joint damping: implicit in its Euler integrator
    const std::string path = std::string(SPARSEBODY_BENCH_DIR) + "/bench_" + tag + ".xml";
    std::ofstream(path) << to_mjcf(model, o);
    char err[1000] = "";
    m = mj_loadXML(path.c_str(), nullptr, err, sizeof err);
    if (!m) { std::fprintf(stderr, "MuJoCo: %s\n", err); std::abort(); }
    d = mj_makeData(m);
    // Standing pose; MuJoCo numbers joints depth-first, so coordinates are placed by joint name.
    const auto q = standing(model);
    qpos0.assign(m->nq, 0.0);
    for (int i = 0; i < model.nb; ++i) {
      const auto& b = model.bodies[i];
      const int j = mj_name2id(m, mjOBJ_JOINT, model.names[i].c_str());
      if (j < 0) continue;
      for (int k = 0; k < joint_nq(b.joint); ++k) qpos0[m->jnt_qposadr[j] + k] = q(b.q_index + k);
    }
    reset();
  }
  void reset() {
    mj_resetData(m, d);
    for (size_t k = 0; k < qpos0.size(); ++k) d->qpos[k] = qpos0[k];
    mj_forward(m, d);
  }
  ~Mj() { mj_deleteData(d); mj_deleteModel(m); }
};

template <class M>
void run_mj_step(benchmark::State& st, const M& model, const char* tag) {
  Mj<M> mj(model, true, tag);
  int k = 0;
  long con = 0, steps = 0;
  auto step = [&] {
    if (++k == 60) { k = 0; mj.reset(); }
    mj_step(mj.m, mj.d);
    con += mj.d->ncon;
    ++steps;
  };
  for (auto _ : st) step();
  st.counters["contacts"] = double(con) / double(std::max(1L, steps));
  StepRunner<M> ours(model);
  const double t_ours = time_us(ours, 2000), t_mj = time_us(step, 2000);
  st.counters["ours_us"] = t_ours;
  st.counters["ratio"] = t_mj / t_ours;
}
template <class M>
void run_mj_forward(benchmark::State& st, const M& model, const char* tag) {
  Mj<M> mj(model, false, tag);
  for (int k = 0; k < mj.m->nv; ++k) mj.d->qvel[k] = 0.1 * (k % 7);
  auto fwd = [&] { mj_forward(mj.m, mj.d); };
  for (auto _ : st) fwd();
  Fixture<M> f(model);
  const double t_ours = time_us([&] { aba(f.m, f.d, f.q, f.qd, f.tau, f.qdd); benchmark::DoNotOptimize(f.qdd.data()); }, 20000);
  const double t_mj = time_us(fwd, 20000);
  st.counters["aba_us"] = t_ours;
  st.counters["ratio"] = t_mj / t_ours;
}
template <class M>
void run_mj_rne(benchmark::State& st, const M& model, const char* tag) {
  Mj<M> mj(model, false, tag);
  mj_forward(mj.m, mj.d);
  std::vector<double> res(mj.m->nv);
  auto rne = [&] { mj_rne(mj.m, mj.d, 1, res.data()); benchmark::DoNotOptimize(res.data()); };
  for (auto _ : st) rne();
  Fixture<M> f(model);
  typename M::VecV out(f.m.nv);
  const double t_ours = time_us([&] { rnea(f.m, f.d, f.q, f.qd, f.tau, out); benchmark::DoNotOptimize(out.data()); }, 20000);
  const double t_mj = time_us(rne, 20000);
  st.counters["rnea_us"] = t_ours;
  st.counters["ratio"] = t_mj / t_ours;
}
// MuJoCo's joint-space inertia: mj_kinematics + mj_comPos (the composite inertias' inputs) + mj_crb,
// the analogue of our crba() with its forward kinematics.
template <class M>
void run_mj_crb(benchmark::State& st, const M& model, const char* tag) {
  Mj<M> mj(model, false, tag);
  for (auto _ : st) {
    mj_kinematics(mj.m, mj.d);
    mj_comPos(mj.m, mj.d);
    mj_crb(mj.m, mj.d);
    benchmark::DoNotOptimize(mj.d->qM);
  }
}
void BM_MjStep_Humanoid34(benchmark::State& st) { run_mj_step(st, h34(), "h34_step"); }
void BM_MjForward_Humanoid34(benchmark::State& st) { run_mj_forward(st, h34(), "h34_fwd"); }
void BM_MjRne_Humanoid34(benchmark::State& st) { run_mj_rne(st, h34(), "h34_rne"); }
void BM_MjStep_Avatar(benchmark::State& st) { run_mj_step(st, avatar(), "avatar_step"); }
void BM_MjForward_Avatar(benchmark::State& st) { run_mj_forward(st, avatar(), "avatar_fwd"); }
void BM_MjRne_Avatar(benchmark::State& st) { run_mj_rne(st, avatar(), "avatar_rne"); }
void BM_MjCrb_Humanoid34(benchmark::State& st) { run_mj_crb(st, h34(), "h34_crb"); }
void BM_MjCrb_Avatar(benchmark::State& st) { run_mj_crb(st, avatar(), "avatar_crb"); }
BENCHMARK(BM_MjCrb_Humanoid34);
BENCHMARK(BM_MjCrb_Avatar);
BENCHMARK(BM_MjStep_Humanoid34);
BENCHMARK(BM_MjForward_Humanoid34);
BENCHMARK(BM_MjRne_Humanoid34);
BENCHMARK(BM_MjStep_Avatar);
BENCHMARK(BM_MjForward_Avatar);
BENCHMARK(BM_MjRne_Avatar);
#endif

#ifdef SPARSEBODY_HAVE_RBDL
// RBDL 3.3.1 on the identical 34-DoF tree, built through its API: the same bodies (mass, CoM,
// inertia about the CoM), joint frames X_T, joint types (spherical = JointTypeSpherical, the free
// root = JointTypeFloatingBase, knees/elbows = JointTypeRevoluteX) and gravity. Its floating base
// is a translation joint then a spherical one: q = (p, quaternion x y z, ..., w at the end of q),
// qd = (linear velocity in the world, angular in the body), tau = (world force, body torque).
namespace rbdl = RigidBodyDynamics;
namespace rbdl_math = RigidBodyDynamics::Math;

struct RbdlPeer {
  rbdl::Model model;
  std::vector<unsigned> id;  // our body -> RBDL body id
  rbdl_math::VectorNd q, qd, tau, qdd, tau_id;
  rbdl_math::MatrixNd H;

  explicit RbdlPeer(const H34& m) : id(m.nb) {
    if (m.root_body() != 0) { std::fprintf(stderr, "RbdlPeer: the free root must be body 0\n"); std::abort(); }
    model.gravity = rbdl_math::Vector3d(m.gravity.x(), m.gravity.y(), m.gravity.z());
    for (int i = 0; i < m.nb; ++i) {
      const auto& b = m.bodies[i];
      const rbdl::Body body(b.mass, rbdl_math::Vector3d(b.com), rbdl_math::Matrix3d(b.inertia));
      const unsigned parent = b.parent < 0 ? 0 : id[b.parent];
      rbdl_math::SpatialTransform XT(rbdl_math::Matrix3d(b.XT.E), rbdl_math::Vector3d(b.XT.r));
      rbdl::Joint joint;
      switch (b.joint) {
        case JointType::Free: joint = rbdl::Joint(rbdl::JointTypeFloatingBase); XT = rbdl_math::SpatialTransform(); break;
        case JointType::Spherical: joint = rbdl::Joint(rbdl::JointTypeSpherical); break;
        case JointType::Revolute:
          if (b.axis != Vec3<double>::UnitX()) { std::fprintf(stderr, "RbdlPeer: revolute axes other than x\n"); std::abort(); }
          joint = rbdl::Joint(rbdl::JointTypeRevoluteX);
          break;
        default: std::fprintf(stderr, "RbdlPeer: fixed joints are not mapped\n"); std::abort();
      }
      id[i] = model.AddBody(parent, XT, joint, body, m.names[i]);
    }
    q = rbdl_math::VectorNd::Zero(model.q_size);
    qd = qdd = tau = tau_id = rbdl_math::VectorNd::Zero(model.qdot_size);
    H = rbdl_math::MatrixNd::Zero(model.qdot_size, model.qdot_size);  // RBDL writes only the non-zero blocks
  }
  // RBDL's first DoF of our body i (the free root: its translation, then rotation at + 3).
  int dof(const H34& m, int i) const {
    return m.bodies[i].joint == JointType::Free ? 0 : int(model.mJoints[id[i]].q_index);
  }
  // Our state and torques to RBDL's coordinates.
  void set(const H34& m, const H34::VecQ& q0, const H34::VecV& qd0, const H34::VecV& tau0) {
    for (int i = 0; i < m.nb; ++i) {
      const auto& b = m.bodies[i];
      const int k = dof(m, i), qi = b.q_index, vi = b.v_index;
      switch (b.joint) {
        case JointType::Free: {
          const Mat3<double> R = read_quat<double>(q0, qi + 3).toRotationMatrix();
          for (int r = 0; r < 3; ++r) q[k + r] = q0(qi + r);
          model.SetQuaternion(id[i], rbdl_math::Quaternion(q0(qi + 4), q0(qi + 5), q0(qi + 6), q0(qi + 3)), q);
          const Vec3<double> v = R * Vec3<double>(qd0.segment<3>(vi + 3)), f = R * Vec3<double>(tau0.segment<3>(vi + 3));
          for (int r = 0; r < 3; ++r) {
            qd[k + r] = v(r); qd[k + 3 + r] = qd0(vi + r);
            tau[k + r] = f(r); tau[k + 3 + r] = tau0(vi + r);
          }
          break;
        }
        case JointType::Spherical:
          model.SetQuaternion(id[i], rbdl_math::Quaternion(q0(qi + 1), q0(qi + 2), q0(qi + 3), q0(qi)), q);
          for (int r = 0; r < 3; ++r) { qd[k + r] = qd0(vi + r); tau[k + r] = tau0(vi + r); }
          break;
        default: q[k] = q0(qi); qd[k] = qd0(vi); tau[k] = tau0(vi); break;
      }
    }
  }
  // RBDL's generalised acceleration to ours (root: p'' = R (dv + w x v) back to dv).
  H34::VecV acceleration(const H34& m, const H34::VecQ& q0, const H34::VecV& qd0) const {
    H34::VecV a(m.nv);
    for (int i = 0; i < m.nb; ++i) {
      const auto& b = m.bodies[i];
      const int k = dof(m, i), vi = b.v_index;
      if (b.joint == JointType::Free) {
        const Mat3<double> R = read_quat<double>(q0, b.q_index + 3).toRotationMatrix();
        const Vec3<double> w = qd0.segment<3>(vi), v = qd0.segment<3>(vi + 3);
        const Vec3<double> pdd(qdd[k], qdd[k + 1], qdd[k + 2]);
        a.segment<3>(vi) = Vec3<double>(qdd[k + 3], qdd[k + 4], qdd[k + 5]);
        a.segment<3>(vi + 3) = R.transpose() * pdd - w.cross(v);
      } else {
        for (int r = 0; r < joint_nv(b.joint); ++r) a(vi + r) = qdd[k + r];
      }
    }
    return a;
  }
};

// Once, before timing: RBDL's ABA, RNEA and CRBA must equal ours on the benchmark state.
bool rbdl_matches(RbdlPeer& p) {
  Fixture<H34> f(h34());
  f.d.implicit_diagonal.setZero();  // RBDL has no implicit damping: plain forward dynamics
  aba(f.m, f.d, f.q, f.qd, f.tau, f.qdd);
  p.set(f.m, f.q, f.qd, f.tau);
  rbdl::ForwardDynamics(p.model, p.q, p.qd, p.tau, p.qdd);
  const H34::VecV a = p.acceleration(f.m, f.q, f.qd);
  const double e_aba = (a - f.qdd).norm() / f.qdd.norm();
  // RNEA: RBDL's inverse dynamics of its own ABA result gives back its tau.
  rbdl::InverseDynamics(p.model, p.q, p.qd, p.qdd, p.tau_id);
  const double e_rnea = (p.tau_id - p.tau).norm() / p.tau.norm();
  H34::VecV tau_ours;
  rnea(f.m, f.d, f.q, f.qd, f.qdd, tau_ours);
  const double e_rnea_ours = (tau_ours - f.tau).norm() / f.tau.norm();
  // CRBA: H_rbdl = P^-T H P^-1 with v = P^-1 qd_rbdl (root block: v_b = R^T p', w_b = w).
  CrbaData<double, 16, 40> out(f.m);
  crba(f.m, f.d, f.q, out);
  rbdl::CompositeRigidBodyAlgorithm(p.model, p.q, p.H, true);
  Eigen::MatrixXd Pinv = Eigen::MatrixXd::Identity(f.m.nv, f.m.nv);
  Pinv.block<3, 3>(0, 0).setZero();
  Pinv.block<3, 3>(0, 3).setIdentity();
  Pinv.block<3, 3>(3, 3).setZero();
  Pinv.block<3, 3>(3, 0) = read_quat<double>(f.q, 3).toRotationMatrix().transpose();
  // Our DoF order equals RBDL's (bodies added in our order, root translation first, then rotation).
  const Eigen::MatrixXd Hr = Pinv.transpose() * Eigen::MatrixXd(out.M) * Pinv;
  const double e_crba = (Hr - p.H).norm() / p.H.norm();
  std::printf("RBDL 3.3.1 vs sparsebody on the 34-DoF tree (relative): ABA %.1e, RNEA %.1e (ours %.1e), CRBA %.1e\n", e_aba,
              e_rnea, e_rnea_ours, e_crba);
  return e_aba < 1e-9 && e_rnea < 1e-9 && e_crba < 1e-9;
}

RbdlPeer& rbdl_peer() {
  static RbdlPeer p = [] {
    RbdlPeer r(h34());
    Fixture<H34> f(h34());
    r.set(f.m, f.q, f.qd, f.tau);
    return r;
  }();
  return p;
}
void BM_RbdlABA_Humanoid34(benchmark::State& st) {
  RbdlPeer& p = rbdl_peer();
  for (auto _ : st) {
    rbdl::ForwardDynamics(p.model, p.q, p.qd, p.tau, p.qdd);
    benchmark::DoNotOptimize(p.qdd.data());
  }
}
void BM_RbdlRNEA_Humanoid34(benchmark::State& st) {
  RbdlPeer& p = rbdl_peer();
  for (auto _ : st) {
    rbdl::InverseDynamics(p.model, p.q, p.qd, p.tau, p.tau_id);  // qdd = the fixture's tau, as BM_RNEA
    benchmark::DoNotOptimize(p.tau_id.data());
  }
}
void BM_RbdlCRBA_Humanoid34(benchmark::State& st) {
  RbdlPeer& p = rbdl_peer();
  for (auto _ : st) {
    rbdl::CompositeRigidBodyAlgorithm(p.model, p.q, p.H, true);
    benchmark::DoNotOptimize(p.H.data());
  }
}
BENCHMARK(BM_RbdlABA_Humanoid34);
BENCHMARK(BM_RbdlRNEA_Humanoid34);
BENCHMARK(BM_RbdlCRBA_Humanoid34);
#endif

// ratio_report.hpp's reporter that also keeps each benchmark's CPU time: on a shared, loaded
// machine a benchmark's real time includes the time it was preempted, its CPU time does not.
class RatioReporter : public sparsebody_bench::CollectingReporter {
 public:
  std::map<std::string, double> cpu_ns;  // name -> CPU time per iteration (ns), the median when repeated
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs)  // aggregates come after their repetitions: the median is written last
      if (!r.error_occurred && (r.run_type != Run::RT_Aggregate || r.aggregate_name == "median"))
        cpu_ns[r.run_name.str()] = r.GetAdjustedCPUTime() * 1e9 / benchmark::GetTimeUnitMultiplier(r.time_unit);
    CollectingReporter::ReportRuns(runs);
  }
};

int run_with_ratios(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RatioReporter rep;
  benchmark::RunSpecifiedBenchmarks(&rep);
  std::printf("\nsparsebody dynamics: ratios measured in this run (time of first / time of second)\n");
  std::printf("  %-58s %27s   %27s\n", "", "real time", "CPU time");
  for (const sparsebody_bench::Ratio& r : sparsebody_bench::ratios()) {
    auto a = rep.times_ns.find(r.numerator), b = rep.times_ns.find(r.denominator);
    auto ca = rep.cpu_ns.find(r.numerator), cb = rep.cpu_ns.find(r.denominator);
    if (a == rep.times_ns.end() || b == rep.times_ns.end() || ca == rep.cpu_ns.end() || cb == rep.cpu_ns.end()) continue;
    std::printf("  %-58s %7.3f / %7.3f us = %5.2f   %7.3f / %7.3f us = %5.2f\n", r.label.c_str(), a->second / 1e3,
                b->second / 1e3, a->second / b->second, ca->second / 1e3, cb->second / 1e3, ca->second / cb->second);
  }
  benchmark::Shutdown();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  using sparsebody_bench::add_ratio;
  add_ratio("ABA 34-DoF: one-body pass-2 steps / paired", "BM_ABAOneBodySteps_Humanoid34", "BM_ABA_Humanoid34");
  add_ratio("ABA avatar: one-body pass-2 steps / paired", "BM_ABAOneBodySteps_Avatar", "BM_ABA_Avatar");
#ifdef SPARSEBODY_HAVE_RBDL
  RbdlPeer check(h34());
  if (!rbdl_matches(check)) {
    std::fprintf(stderr, "bench_dynamics: RBDL's model does not match ours; no comparison\n");
    return 1;
  }
  add_ratio("CRBA 34-DoF: RBDL / sparsebody", "BM_RbdlCRBA_Humanoid34", "BM_CRBA_Humanoid34");
  add_ratio("ABA 34-DoF: RBDL ForwardDynamics / sparsebody", "BM_RbdlABA_Humanoid34", "BM_ABA_Humanoid34");
  add_ratio("RNEA 34-DoF: RBDL InverseDynamics / sparsebody", "BM_RbdlRNEA_Humanoid34", "BM_RNEA_Humanoid34");
#endif
#ifdef SPARSEBODY_HAVE_MUJOCO
  for (const char* model : {"Humanoid34", "Avatar"}) {
    const std::string m = model;
    add_ratio("CRBA " + m + ": MuJoCo kinematics+comPos+crb / sparsebody", "BM_MjCrb_" + m, "BM_CRBA_" + m);
    add_ratio("ABA " + m + ": MuJoCo mj_forward (no contact) / sparsebody", "BM_MjForward_" + m, "BM_ABA_" + m);
    add_ratio("RNEA " + m + ": MuJoCo mj_rne / sparsebody", "BM_MjRne_" + m, "BM_RNEA_" + m);
    add_ratio("Step " + m + ": MuJoCo mj_step / sparsebody", "BM_MjStep_" + m, "BM_Step_" + m);
  }
#endif
  return run_with_ratios(argc, argv);
}


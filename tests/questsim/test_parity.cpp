// Observation and policy against the PyTorch reference (weights_tool/questsim), run at test time:
// this test simulates a double-precision avatar (1.62 m) under random torques, writes the model
// JSON and a few states (q, v, contact forces, a random sensor window, the height) to case.json,
// runs `python3 -m weights_tool.questsim reference` (an independent torch forward kinematics from
// the model JSON), and compares the observation and the policy output (float <= 1e-4).
#include <fstream>
#include <random>

#include <nlohmann/json.hpp>

#include "questsim/common.hpp"
#include "sparsebody/dynamics/model_json.hpp"

using namespace sparsebody;
using namespace sparsebody::control;
using namespace sparsebody::avatar;
using dynamics::Vec3;

namespace {
constexpr int NB = character::kDefaultAvatarBodies, NJ = character::kDefaultAvatarJointDofs, NF = 6;
using L = QuestSimLayout<NB, NJ, NF>;
using Model = dynamics::Model<double, 24, 72>;
using Sim = dynamics::Simulator<double, 24, 72>;
using Builder = QuestSimObservationBuilder<double, 24, 72>;
using NetF = networks::QuestSimPolicyNet<float, L::size, NJ>;
using NetH = networks::QuestSimPolicyNet<float, L::size, NJ, nn::f16>;
using NetQ = networks::QuestSimPolicyNet<float, L::size, NJ, nn::q8>;

struct Case {
  std::array<double, L::size> obs64{};
  std::array<float, L::size> obs32{};
  std::array<float, L::size> obs_float_sim{};  // state, FK and observation in float
};

nlohmann::json vec(const Eigen::Ref<const Eigen::VectorXd>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (int i = 0; i < v.size(); ++i) a.push_back(v(i));
  return a;
}

// The double-precision avatar (1.62 m) of the parity case, with the controller's joint damping.
Model parity_model(double height) {
  Model m = character::avatar_for_user_height<double>(height);
  for (int i = 1; i < m.nb; ++i) m.bodies[i].damping = 0.1;
  m.finalize();
  return m;
}

// A random sensor window (positions around 1.5 m, random rotations) and its JSON (p, quaternion).
Builder::UserWindow random_window(std::mt19937& rng, std::normal_distribution<double>& n, nlohmann::json& uj) {
  Builder::UserWindow user;
  uj = nlohmann::json::array();
  for (auto& fr : user) {
    nlohmann::json fj = nlohmann::json::array();
    for (auto& d : fr) {
      d.position = Vec3<double>(0.3 * n(rng), 1.5 + 0.1 * n(rng), 0.3 * n(rng));
      const Eigen::Quaterniond r = dynamics::quat_exp(Vec3<double>(n(rng), n(rng), n(rng)));
      d.rotation = r.toRotationMatrix();
      fj.push_back({d.position.x(), d.position.y(), d.position.z(), r.w(), r.x(), r.y(), r.z()});
    }
    uj.push_back(fj);
  }
  return user;
}

// The controller's float path: the same state computed entirely in float (FK included).
void float_path_observation(const Model& m, const Sim& sim, const Builder::UserWindow& user, const std::array<Vec3<double>, 2>& ff,
                            double height, float* out) {
  const auto mf = m.cast<float>();
  dynamics::Data<float, 24, 72> df(mf);
  const dynamics::Model<float, 24, 72>::VecQ qf = sim.q().cast<float>();
  const dynamics::Model<float, 24, 72>::VecV vf = sim.v().cast<float>();
  dynamics::forward_kinematics(mf, df, qf, &vf);
  std::array<QuestSimSensorFrame<float>, NF + 1> uf;
  for (int t = 0; t <= NF; ++t)
    for (int d = 0; d < 3; ++d) {
      uf[t][d].position = user[t][d].position.cast<float>();
      uf[t][d].rotation = user[t][d].rotation.cast<float>();
    }
  const std::array<Vec3<float>, 2> fff{ff[0].cast<float>(), ff[1].cast<float>()};
  build_quest_sim_observation<NB, NJ, NF>(mf, df, qf, vf, fff, uf, float(height), out);
}

// 8 states of the avatar under random torques (start bent, moving, slightly above the floor; a
// state every 7 substeps), each with a random sensor window: the C++ observations (double, float,
// all-float) into `cases` and the states into the case JSON `cj`.
std::vector<Case> simulate_cases(const Model& m, double height, nlohmann::json& cj) {
  Sim sim(m);
  sim.options.mode = dynamics::ControlMode::Torque;
  const Builder builder(m);
  std::mt19937 rng(11);
  std::normal_distribution<double> n;
  std::uniform_real_distribution<double> u(-1, 1);
  cj["model"] = nlohmann::json::parse(dynamics::model_to_json(m));
  cj["future"] = NF;
  cj["states"] = nlohmann::json::array();
  std::vector<Case> cases;
  auto q = sim.q();
  auto v = sim.v();
  q(1) += 0.01;
  for (int k = 0; k < m.nv; ++k) v(k) = 0.3 * n(rng);
  q(3) = std::cos(0.35); q(5) = std::sin(0.35);  // yawed root
  sim.set_state(q, v);
  int with_contacts = 0;
  for (int c = 0; c < 8; ++c) {
    for (int s = 0; s < 7; ++s) {
      for (int k = 6; k < m.nv; ++k) sim.torques()(k) = 2 * u(rng);
      REQUIRE(sim.step(1.0 / 72) == dynamics::StepStatus::Ok);
    }
    nlohmann::json uj;
    const Builder::UserWindow user = random_window(rng, n, uj);
    nlohmann::json contacts = nlohmann::json::array();
    for (int k = 0; k < sim.num_contacts(); ++k) {
      const auto& ct = sim.contact_at(k);
      if (ct.active) contacts.push_back({ct.body, ct.force.x(), ct.force.y(), ct.force.z()});
    }
    const auto ff = builder.foot_forces(sim);
    with_contacts += (ff[0].norm() + ff[1].norm()) > 1.0;
    cj["states"].push_back({{"q", vec(sim.q())}, {"v", vec(sim.v())}, {"contacts", contacts}, {"user", uj}, {"height", height}});
    Case cs;
    builder.build(sim, user, height, cs.obs64.data());
    builder.build(sim, user, height, cs.obs32.data());
    float_path_observation(m, sim, user, ff, height, cs.obs_float_sim.data());
    cases.push_back(cs);
  }
  CHECK(with_contacts >= 2);  // the foot-force block is exercised with non-zero values
  return cases;
}

// `python3 -m weights_tool.questsim reference` on the case file with the given policy weights.
nlohmann::json torch_reference(const std::string& case_path, const std::string& weights, const std::string& out) {
  const std::string cmd = std::string("cd \"") + SPARSEBODY_SOURCE_DIR + "\" && \"" + SPARSEBODY_PYTHON_EXE +
                          "\" -m weights_tool.questsim reference --case \"" + case_path + "\" --weights \"" + weights +
                          "\" --out \"" + out + "\"";
  REQUIRE(std::system(cmd.c_str()) == 0);
  nlohmann::json ref;
  std::ifstream(out) >> ref;
  return ref;
}

// Largest differences against the reference.
struct Errors {
  double obs_fsim = 0, obs64 = 0, obs32 = 0, pol = 0, chain = 0, f16 = 0, max_abs_obs = 0, full = 0, max_abs_full = 0, q8 = 0;
};

// The observations, and the policies (float, f16; the full-gain one in float and q8) on them,
// against the reference outputs `ref` (controller policy) and `ref_full` (full-gain policy).
Errors compare(const std::vector<Case>& cases, const nlohmann::json& ref, const nlohmann::json& ref_full, const std::string& policy_full) {
  auto wf = nn::NetworkWeights<NetF>::load(questsim_test::policy_path(), networks::kQuestSimPolicyKind);
  auto wh = nn::NetworkWeights<NetH>::load(questsim_test::policy_path(), networks::kQuestSimPolicyKind);
  auto wfull = nn::NetworkWeights<NetF>::load(policy_full, networks::kQuestSimPolicyKind);
  nn::Network<NetF> pf(wf), pfull(wfull);
  nn::Network<NetH> ph(wh);
  auto wq = nn::NetworkWeights<NetQ>::load(policy_full, networks::kQuestSimPolicyKind);
  nn::Network<NetQ> pq(wq);
  Errors e;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const auto& ro = ref["observations"][c];
    REQUIRE(ro.size() == std::size_t(L::size));
    std::array<float, L::size> torch_obs32{};
    for (int i = 0; i < L::size; ++i) {
      const double r = ro[i].get<double>();
      e.max_abs_obs = std::max(e.max_abs_obs, std::abs(r));
      e.obs64 = std::max(e.obs64, std::abs(cases[c].obs64[i] - r));
      e.obs32 = std::max(e.obs32, std::abs(double(cases[c].obs32[i]) - r));
      e.obs_fsim = std::max(e.obs_fsim, std::abs(double(cases[c].obs_float_sim[i]) - r) / std::max(1.0, std::abs(r)));
      torch_obs32[i] = float(r);
    }
    const auto& a32 = ref["actions32"][c];
    const auto& a64 = ref["actions64"][c];
    const float* y = pf.step(torch_obs32.data());  // policy alone, same input as torch float32
    for (int k = 0; k < NJ; ++k) e.pol = std::max(e.pol, std::abs(double(y[k]) - a32[k].get<double>()));
    y = pf.step(cases[c].obs32.data());             // whole chain: C++ observation -> C++ policy
    for (int k = 0; k < NJ; ++k) e.chain = std::max(e.chain, std::abs(double(y[k]) - a64[k].get<double>()));
    y = pfull.step(torch_obs32.data());
    for (int k = 0; k < NJ; ++k) {
      const double r = ref_full["actions32"][c][k].get<double>();
      e.full = std::max(e.full, std::abs(double(y[k]) - r));
      e.max_abs_full = std::max(e.max_abs_full, std::abs(r));
    }
    y = pq.step(torch_obs32.data());  // int8 weights, full-gain policy: approximate by construction
    for (int k = 0; k < NJ; ++k) e.q8 = std::max(e.q8, std::abs(double(y[k]) - ref_full["actions64"][c][k].get<double>()));
    y = ph.step(cases[c].obs32.data());
    for (int k = 0; k < NJ; ++k) e.f16 = std::max(e.f16, std::abs(double(y[k]) - a64[k].get<double>()));
  }
  return e;
}
}  // namespace

TEST_CASE("QuestSim parity: observation and policy against PyTorch (weights_tool/questsim)") {
  const double height = 1.62;
  const Model m = parity_model(height);
  nlohmann::json cj;
  const std::vector<Case> cases = simulate_cases(m, height, cj);

  const std::string dir = SPARSEBODY_QUESTSIM_WORK_DIR;
  const std::string case_path = dir + "/parity_case.json";
  std::ofstream(case_path) << cj.dump();
  const nlohmann::json ref = torch_reference(case_path, questsim_test::policy_path(), dir + "/parity_reference.json");
  // The same observations through a policy with a full-gain output layer (outputs spread over
  // [-1, 1] instead of the controller policy's +/-0.05): a policy-only check at full range.
  const std::string policy_full = dir + "/questsim_policy_gain1.json";
  const nlohmann::json ref_full = torch_reference(case_path, policy_full, dir + "/parity_reference_gain1.json");
  REQUIRE(ref["observations"].size() == cases.size());

  const Errors e = compare(cases, ref, ref_full, policy_full);
  MESSAGE("max |obs| " << e.max_abs_obs << "; observation double err " << e.obs64 << ", float err " << e.obs32
                       << ", all-float (FK in float) err relative to max(1, |ref|) " << e.obs_fsim
                       << "; policy float err " << e.pol << "; obs+policy float err " << e.chain
                       << "; obs+policy f16-weights err " << e.f16 << "; full-gain policy err " << e.full
                       << " (max |a| " << e.max_abs_full << "); full-gain policy, q8 weights err " << e.q8);
  CHECK(e.obs64 < 1e-9);
  CHECK(e.obs32 < 1e-4);
  CHECK(e.obs_fsim < 1e-4);
  CHECK(e.pol < 1e-4);
  CHECK(e.chain < 1e-4);
  CHECK(e.full < 1e-4);
  CHECK(e.max_abs_full > 0.5);
  CHECK(e.f16 < 2e-2);  // weights rounded to 11 significant bits: looser by construction
  CHECK(e.q8 < 0.1);    // 8-bit weights and inputs (nn/int8.hpp): an approximation (0.052 measured)
}

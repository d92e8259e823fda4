// Python binding of the QuestSim training environment (include/sparsebody/training/questsim_env.hpp).
// Observations, rewards and flags are numpy views of the environment's own buffers (zero copy, valid
// while the Env lives; step() overwrites them in place); actions are read in place from a C-contiguous
// float32 array. step() releases the GIL.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "sparsebody/predict/n3p_predictor.hpp"
#include "sparsebody/training/n3p_env.hpp"
#include "sparsebody/training/questsim_env.hpp"

namespace py = pybind11;
using namespace sparsebody;
using Env = training::QuestSimEnv<6>;

namespace {

struct Clips {
  std::shared_ptr<std::vector<training::QuestSimReference>> clips = std::make_shared<std::vector<training::QuestSimReference>>();
  predict::N3PMeta meta;
};

// The standard skeleton and standing heights come from the Neural3Points lower-body weights' meta
// (the same retarget the physics pipeline uses).
std::shared_ptr<Clips> load_clips(const std::vector<std::string>& paths, const std::string& n3p_lower, double rate) {
  using Lo = predict::N3PPredictor<float>::LoNet;
  auto c = std::make_shared<Clips>();
  c->meta = predict::N3PMeta::from(nn::NetworkWeights<Lo>::load(n3p_lower, networks::kN3PLowerKind)->info());
  {
    py::gil_scoped_release nogil;
    for (const auto& p : paths) c->clips->push_back(training::read_questsim_reference(p, c->meta.skeleton, rate));
  }
  return c;
}

// A read-only property `name`: the zero-copy view of get(env), [size] when cols is 0, else
// [size, cols]; the view keeps the environment alive.
template <class E, class Get>
void bind_view(py::class_<E>& c, const char* name, Get get, int cols) {
  c.def_property_readonly(name, [get, cols](py::object self) {
    E& e = self.cast<E&>();
    using T = std::remove_const_t<std::remove_pointer_t<decltype(get(e))>>;
    std::vector<py::ssize_t> shape{e.size()};
    if (cols) shape.push_back(cols);
    return py::array(py::array_t<T>(shape, const_cast<T*>(get(e)), self));
  });
}

// What both environments bind alike: sizes, zero-copy views of their buffers, step and the
// per-character queries. `terms`: columns of reward_terms.
template <class E>
void bind_common(py::class_<E>& c, int terms) {
  bind_view(c, "obs", [](E& e) { return e.observations(); }, E::kObservationSize);
  bind_view(c, "final_obs", [](E& e) { return e.final_observations(); }, E::kObservationSize);
  bind_view(c, "reward", [](E& e) { return e.rewards(); }, 0);
  bind_view(c, "reward_terms", [](E& e) { return e.reward_terms(); }, terms);
  bind_view(c, "terminated", [](E& e) { return e.terminated(); }, 0);
  bind_view(c, "truncated", [](E& e) { return e.truncated(); }, 0);
  c.def_property_readonly_static("obs_size", [](py::object) { return E::kObservationSize; })
      .def_property_readonly_static("action_size", [](py::object) { return E::kActionSize; })
      .def("__len__", &E::size)
      .def("step", [](E& e, py::array_t<float, py::array::c_style> a, int threads) {
        if (a.ndim() != 2 || a.shape(0) != e.size() || a.shape(1) != E::kActionSize)
          throw py::value_error("actions: expected float32 [" + std::to_string(e.size()) + ", " +
                                std::to_string(E::kActionSize) + "]");
        const float* p = a.data();
        py::gil_scoped_release nogil;
        e.step(p, threads);
      }, py::arg("actions"), py::arg("threads") = 1)
      .def("reset_all", &E::reset_all)
      .def("set_residual", &E::set_residual, py::arg("max_force"), py::arg("max_torque"))
      .def("clip", &E::clip)
      .def("frame", &E::frame)
      .def("episode_step", &E::episode_step)
      .def("q", [](const E& e, int i) {
        const auto& q = e.simulator(i).q();
        return std::vector<double>(q.data(), q.data() + q.size());
      })
      .def("reference_q", [](const E& e, int i) {
        const auto& q = e.reference_q(i);
        return std::vector<double>(q.data(), q.data() + q.size());
      });
}

}  // namespace

PYBIND11_MODULE(_questsim_env, m) {
  m.doc() = "sparsebody QuestSim training environment (batched, C++)";
  py::class_<Clips, std::shared_ptr<Clips>>(m, "Clips")
      .def("__len__", [](const Clips& c) { return c.clips->size(); })
      .def("frames", [](const Clips& c, int i) { return c.clips->at(std::size_t(i)).frames(); })
      .def("source", [](const Clips& c, int i) { return c.clips->at(std::size_t(i)).source; });
  m.def("load_clips", &load_clips, py::arg("paths"), py::arg("n3p_lower"), py::arg("rate") = 36.0,
        "BVH clips -> reference motions at `rate` Hz (poses and device-stream sensors): 36 for QuestSim, 30 for N3PEnv");

  py::class_<training::QuestSimEnvConfig>(m, "Config")
      .def(py::init<>())
      .def_readwrite("max_head_error", &training::QuestSimEnvConfig::max_head_error)
      .def_readwrite("max_episode_steps", &training::QuestSimEnvConfig::max_episode_steps)
      .def_readwrite("neutral_start", &training::QuestSimEnvConfig::neutral_start)
      .def_readwrite("expert", &training::QuestSimEnvConfig::expert)
      .def_readwrite("expert_wn", &training::QuestSimEnvConfig::expert_wn)
      .def_readwrite("expert_support", &training::QuestSimEnvConfig::expert_support)
      .def_readwrite("expert_friction", &training::QuestSimEnvConfig::expert_friction)
      .def_readwrite("expert_cop_radius", &training::QuestSimEnvConfig::expert_cop_radius)
      .def_readwrite("expert_yaw_radius", &training::QuestSimEnvConfig::expert_yaw_radius)
      .def_readwrite("expert_support_height", &training::QuestSimEnvConfig::expert_support_height)
      .def_readwrite("expert_feedforward", &training::QuestSimEnvConfig::expert_feedforward)
      .def_readwrite("expert_lead", &training::QuestSimEnvConfig::expert_lead)
      .def_readwrite("joint_armature", &training::QuestSimEnvConfig::joint_armature)
      .def_readwrite("joint_damping", &training::QuestSimEnvConfig::joint_damping)
      .def_readwrite("expert_pd_kp", &training::QuestSimEnvConfig::expert_pd_kp)
      .def_readwrite("expert_pd_kd", &training::QuestSimEnvConfig::expert_pd_kd)
      .def_readwrite("record_reference", &training::QuestSimEnvConfig::record_reference)
      .def_readwrite("residual_max_force", &training::QuestSimEnvConfig::residual_max_force)
      .def_readwrite("residual_max_torque", &training::QuestSimEnvConfig::residual_max_torque)
      .def_property("reward_mean_over_joints", [](const training::QuestSimEnvConfig& c) { return c.reward.mean_over_joints; },
                    [](training::QuestSimEnvConfig& c, bool b) { c.reward.mean_over_joints = b; })
      .def_property("reward_w", [](const training::QuestSimEnvConfig& c) { return c.reward.w; },
                    [](training::QuestSimEnvConfig& c, std::array<double, 5> w) { c.reward.w = w; })
      .def_property("reward_k", [](const training::QuestSimEnvConfig& c) { return c.reward.k; },
                    [](training::QuestSimEnvConfig& c, std::array<double, 5> k) { c.reward.k = k; });

  py::class_<Env> env(m, "Env");
  bind_common(env, 5);
  bind_view(env, "expert_actions", [](Env& e) { return e.expert_actions(); }, Env::kActionSize);
  bind_view(env, "reference_obs", [](Env& e) { return e.reference_observations(); }, Env::kObservationSize);
  bind_view(env, "frames", [](Env& e) { return e.frames(); }, Env::kFrameSize);
  bind_view(env, "final_frames", [](Env& e) { return e.final_frames(); }, Env::kFrameSize);
  env.def(py::init([](std::shared_ptr<Clips> c, const std::vector<double>& heights, unsigned long long seed,
                      training::QuestSimEnvConfig cfg) { return std::make_unique<Env>(c->clips, c->meta, heights, seed, cfg); }),
          py::arg("clips"), py::arg("heights"), py::arg("seed") = 0, py::arg("config") = training::QuestSimEnvConfig{})
      .def("residual_force", &Env::root_residual_force)
      .def("sensor_positions", [](const Env& e, int i) {
        py::array_t<double> out({3, 3});
        auto r = out.mutable_unchecked<2>();
        for (int d = 0; d < 3; ++d)
          for (int k = 0; k < 3; ++k) r(d, k) = e.sensor(i)[d].position(k);
        return out;
      })
      .def("body_names", [](const Env& e) {
        std::vector<std::string> n;
        for (int b = 0; b < e.model(0).nb; ++b) n.push_back(e.model(0).names[b]);
        return n;
      })
      .def("body_positions", [](const Env& e, int i) {
        const auto& d = e.simulator(i).data();
        py::array_t<double> out({e.model(i).nb, 3});
        auto r = out.mutable_unchecked<2>();
        for (int b = 0; b < e.model(i).nb; ++b)
          for (int k = 0; k < 3; ++k) r(b, k) = double(d.p[b](k));
        return out;
      });
  // Neural3Points correction-policy environment (include/sparsebody/training/n3p_env.hpp).
  py::class_<training::N3PEnvConfig>(m, "N3PConfig")
      .def(py::init<>())
      .def_readwrite("action_scale", &training::N3PEnvConfig::action_scale)
      .def_readwrite("max_episode_steps", &training::N3PEnvConfig::max_episode_steps)
      .def_readwrite("rest_start", &training::N3PEnvConfig::rest_start)
      .def_readwrite("contact_height", &training::N3PEnvConfig::contact_height)
      .def_readwrite("residual_weight", &training::N3PEnvConfig::residual_weight)
      .def_property("max_force", [](const training::N3PEnvConfig& c) { return c.controller.max_force; },
                    [](training::N3PEnvConfig& c, double v) { c.controller.max_force = v; })
      .def_property("max_torque", [](const training::N3PEnvConfig& c) { return c.controller.max_torque; },
                    [](training::N3PEnvConfig& c, double v) { c.controller.max_torque = v; });

  using NEnv = training::N3PEnv;
  py::class_<NEnv> nenv(m, "N3PEnv");
  bind_common(nenv, 6);
  nenv.def(py::init([](std::shared_ptr<Clips> c, int characters, unsigned long long seed, training::N3PEnvConfig cfg) {
             return std::make_unique<NEnv>(c->clips, c->meta, characters, seed, cfg);
           }),
           py::arg("clips"), py::arg("characters"), py::arg("seed") = 0, py::arg("config") = training::N3PEnvConfig{})
      .def("residual_force", &NEnv::residual_force)
      .def("targets", [](const NEnv& e, int i) {
        const auto& q = e.targets(i);
        return std::vector<double>(q.data(), q.data() + q.size());
      });
}

// What a QuestSim control tick did (avatar/questsim.hpp: tick(), control_step(), last_event()).
#pragma once

namespace sparsebody::avatar {

enum class QuestSimEvent : unsigned char {
  Stepped = 0,        // observation, policy and substeps ran normally
  Waiting,            // no valid headset frame yet: nothing simulated
  TrackerReset,       // tracker restart (long loss, origin jump, time gap): character reset, then stepped
  RejectedAction,     // non-finite observation or policy output: zero torques were applied
  SimulationFailure,  // a substep failed (see last_sim_status()): character reset to standing
  Fall,               // the character fell: reset to standing
};
inline const char* event_name(QuestSimEvent e) {
  switch (e) {
    case QuestSimEvent::Stepped: return "stepped";
    case QuestSimEvent::Waiting: return "waiting";
    case QuestSimEvent::TrackerReset: return "tracker reset";
    case QuestSimEvent::RejectedAction: return "rejected action";
    case QuestSimEvent::SimulationFailure: return "simulation failure";
    default: return "fall";
  }
}

}  // namespace sparsebody::avatar

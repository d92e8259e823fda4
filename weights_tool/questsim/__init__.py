"""QuestSim (Winkler et al., SIGGRAPH Asia 2022) PyTorch reference: the policy observation (§3.3-§3.6)
computed by an independent torch forward kinematics from the model JSON and the state (q, v), the
policy MLP [400, 300, 200] with tanh, and the random-weight policy files the C++ tests and benchmarks
use (trained QuestSim policies are not shipped). C++ side: include/sparsebody/control/questsim_*.hpp.
"""

"""Neural3Points pose predictor (Ye et al., SCA 2022, §4): the training and reference side.

Modules, in data-flow order:
  layout    joint sets J_up / J_lo, the layouts of o (trackers), g_lo, g_up, z; heading frame h algebra
  dataset   BVH clips (the LoBSTr engineer's loader, weights_tool/lobstr) -> world-space arrays
  model     the three sub-predictors with their normalisation, and the batched Eq. (2) rollout
  train     pretraining of G_sig, G_lo, G_up, then joint fine-tuning of G_sig + G_lo (G_up frozen)
  evaluate  MPJPE full/upper/lower, MPJRE, jitter, foot skating, for 3-point and HMD-only input
  export    checkpoints -> three sparsebody weights files (kinds n3p_signal, n3p_lower, n3p_upper)
  golden    the C++ parity golden (synthetic or CMU motion, never Bandai data)

Command line: /usr/bin/python3 -m weights_tool.n3p --help
"""

"""LoBSTr pipeline (Yang et al., Eurographics 2021) in Python: the training and reference side.

Modules, in data-flow order:
  bvh        BVH reader (any channel order/count) and forward kinematics
  rotations  rotation matrices, yaw frames and the 6D representation used by the pipeline
  skeleton   the standard skeleton, joint-name mapping across skeletons, tracker synthesis, contacts
  features   the 37 velocity features of the paper's Appendix 1 (the reference the C++ side must match)
  dataset    clips -> cached feature/target arrays
  train      training with the paper's losses (pose L1, FK, foot velocity, contact cross-entropy)
  evaluate   Table 1 metrics (+ MPJPE, jitter, foot skating) on the validation split
  export     checkpoint -> sparsebody weights JSON with the pipeline metadata
  golden     the parity golden for the C++ pipeline test (synthetic or CMU motion, never Bandai data)

Command line: /usr/bin/python3 -m weights_tool.lobstr --help
"""

"""Neural3Points physics mode: PyTorch reference of the control-policy input and policy."""

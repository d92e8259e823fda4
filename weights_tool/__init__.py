"""sparsebody weights tool: PyTorch reference modules, the JSON weights exporter and golden vectors.

Run from the repository root with Debian's Python: ``/usr/bin/python3 -m weights_tool --help``.
"""
FORMAT = "sparsebody-weights"
VERSION = 1

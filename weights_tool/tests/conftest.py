import os
import sys

# Make `import weights_tool` work when pytest runs from anywhere.
sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))

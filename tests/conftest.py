import os

import matplotlib

matplotlib.use("Agg")
os.environ.setdefault("SHAKEDOWN_NOTEBOOK_SMALL", "1")

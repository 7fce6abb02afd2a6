"""Checks of the stroke kernel that several test files make (not a test file itself).

- :func:`scalar_strokes`: the kernel's strokes of design rows in a fresh interpreter with
  ``SC_SCALAR=1`` (the lane-by-lane code), to compare bit for bit with the SIMD lanes;
- :func:`energy_rise_ratio`: the early exit's energy rule on one full stroke -- after the
  exit node the energy never rises above its value there by more than the margin
  2 (steps left) g + 1e-12 E_scale (g: the largest one-step gain before the exit).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np

_SCALAR_RUN = """
import json, sys
import numpy as np
from softclose.simulation.kernel import binding
from softclose.config import default_config
from softclose.simulation.simulator import Simulator
sim = Simulator.from_config(default_config()); st = sim.stroke
D = np.array(json.loads(sys.stdin.read()), dtype=float)
out = binding.run_strokes(sim.table, sim.method, sim.step, st.t_max, st.theta0, st.theta_closed, D)
sys.stdout.write(json.dumps([out.tobytes().hex(), out.shape[1]]))
"""


def scalar_strokes(D: np.ndarray) -> np.ndarray:
    """binding.run_strokes of the default config's simulator on rows ``D`` (NaN allowed),
    lane by lane (SC_SCALAR=1, a fresh interpreter)."""
    env = dict(os.environ, SC_SCALAR="1")
    rows = np.where(np.isnan(D), None, D).tolist()
    res = subprocess.run([sys.executable, "-c", _SCALAR_RUN], input=json.dumps(rows),
                         capture_output=True, text=True, env=env, check=True)
    data, width = json.loads(res.stdout)
    return np.frombuffer(bytes.fromhex(data), float).reshape(-1, width)


def energy_rise_ratio(E: np.ndarray, t: np.ndarray, n: int, t_max: float, step: float,
                      scale: float, row=None) -> float:
    """Asserts that the energies ``E`` at the nodes ``t`` of a whole stroke never rise after
    the exit node ``n`` above E[n] + margin (a failure names ``row``); returns the rise over
    the margin."""
    gain = max(0.0, float(np.diff(E[:n + 1]).max()))
    margin = 2 * ((t_max - t[n]) / step + 1) * gain + 1e-12 * scale
    rise = float(E[n + 1:].max() - E[n])
    assert rise <= margin + 1e-15 * scale, (row, rise, margin)
    return rise / margin

"""Design-space sweeps (SPEC §7 ``softclose sweep``): a grid over numeric config keys.

``--grid KEY=START:STOP:COUNT`` (repeatable) spans a full-factorial grid over any numeric
config key (:func:`softclose.config.numeric_keys`): the design keys, and geometry, mass,
stroke, simulate or optimise keys such as ``geometry.spring_anchor[0]`` or ``mass.lid``.
Every point gets the SPEC §4 metrics, the SPEC §5 objective and its feasibility.

How it is evaluated (metric-only, batched):

- rows are grouped by their non-design values; each group builds one :class:`LidModel` and
  :class:`Simulator` (about 0.1 s) and runs its design rows as batches in the C kernel
  (threads, several strokes interleaved per thread, nothing kept per step, nothing
  integrated past the event);
- a group whose geometry cannot close (or any other invalid value) marks its rows
  ``invalid`` with the reason -- the sweep goes on;
- batches are at most :data:`CHUNK` designs, so Ctrl-C stops within a fraction of a
  second and the rows already computed are written;
- a progress bar (designs done, designs/s, time left) goes to stderr when it is a terminal
  and ``--json`` is not given.

Outputs in ``--out DIR``: ``sweep.csv`` (one row a design: the swept keys, the SPEC §4
metrics, ``objective``, then ``feasible``, ``status`` and ``reason``) and, for each pair of
swept keys, ``map_<key1>__<key2>.png``: contour maps of impact_theta_dot, peak_tip_speed,
closing_time and the objective on the slice through the best feasible point, infeasible
regions masked (hatched by reason) and the best feasible point marked. With one swept key,
``profile_<key>.png`` shows the same four quantities as curves.
"""

from __future__ import annotations

import csv
import math
import re
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .config import Config, numeric_keys, to_dict
from .errors import ConfigError, SoftcloseError

#: design keys and their column in the kernel's parameter rows
DESIGN_KEYS = {"design.spring_k": 0, "design.spring_rest_length": 1, "design.damper_c": 2,
               "design.rotary_damper_c": 3}
METRICS = ("closed", "closing_time", "impact_theta_dot", "impact_tip_speed", "peak_tip_speed",
           "min_spring_length", "max_spring_length", "holding_moment")
#: designs per kernel call: bounds the Ctrl-C latency and the progress-bar granularity
CHUNK = 4096
#: largest grid accepted (rows are held in memory and written to one CSV)
MAX_POINTS = 20_000_000
#: reasons a computed design is infeasible (SPEC §5), in the order they are tested
REASONS = ("not closed", "too slow", "too fast", "not held shut", "rebound")

_GRID = re.compile(r"^\s*([^=\s]+)\s*=\s*([^:]*):([^:]*):([^:]*)\s*$")

UNITS = {
    "design.spring_k": ("spring stiffness k", "N/m"),
    "design.spring_rest_length": ("spring rest length l0", "m"),
    "design.damper_c": ("damper c", "N s/m"),
    "design.rotary_damper_c": ("rotary damper c_rot", "N m s/rad"),
    "mass.lid": ("lid mass", "kg"), "mass.crank_oa": ("crank OA mass", "kg"),
    "mass.crank_bc": ("crank BC mass", "kg"), "mass.inertia_lid": ("lid inertia", "kg m²"),
    "mass.inertia_oa": ("crank OA inertia", "kg m²"),
    "mass.inertia_bc": ("crank BC inertia", "kg m²"), "mass.gravity": ("gravity g", "m/s²"),
    "stroke.theta0_deg": ("release angle θ0", "deg"),
    "stroke.theta_closed_deg": ("closed angle", "deg"), "stroke.t_max": ("t_max", "s"),
    "simulate.step": ("integrator step", "s"), "simulate.reference_tol": ("reference tol", "-"),
    "optimise.closing_time_max": ("closing_time_max", "s"),
    "optimise.closing_time_min": ("closing_time_min", "s"),
    "optimise.holding_moment_min": ("holding_moment_min", "N m"),
    "optimise.weight_impact": ("weight_impact", "s²"),
    "optimise.weight_peak_tip": ("weight_peak_tip", "s²/m²"),
}
QUANTITIES = {  # what the maps show: (label, unit)
    "impact_theta_dot": ("impact angular velocity θ'", "rad/s"),
    "peak_tip_speed": ("peak tip speed", "m/s"),
    "closing_time": ("closing time", "s"),
    "objective": ("objective J = w_i θ'² + w_p v_peak²", "-"),
}


def label(key: str) -> str:
    """Axis label with unit for a config key."""
    if key in UNITS:
        name, unit = UNITS[key]
        return f"{name} [{unit}]"
    section = key.split(".")[0]
    if key.startswith("geometry.assembly"):
        return f"{key} [deg]"
    return f"{key} [m]" if section == "geometry" else key


# -- grid --------------------------------------------------------------------------------
@dataclass
class Axis:
    key: str
    values: np.ndarray
    spec: str

    @property
    def is_design(self) -> bool:
        return self.key in DESIGN_KEYS


def parse_grid(specs: list[str], cfg: Config | None = None) -> list[Axis]:
    """Parse ``KEY=START:STOP:COUNT`` strings; every error is a one-line ConfigError."""
    if not specs:
        raise ConfigError("--grid: give at least one KEY=START:STOP:COUNT")
    known = numeric_keys()
    axes: list[Axis] = []
    for spec in specs:
        m = _GRID.match(spec)
        if not m:
            raise ConfigError(f"--grid {spec!r}: expected KEY=START:STOP:COUNT, e.g. "
                              "design.spring_k=0:2000:41")
        key, a, b, n = (g.strip() for g in m.groups())
        if key not in known:
            close = [k for k in known if key.split(".")[-1].split("[")[0] in k]
            hint = f" (did you mean {', '.join(close[:4])}?)" if close else \
                " (numeric keys: section.key or section.key[i], e.g. design.damper_c)"
            raise ConfigError(f"--grid {spec!r}: {key} is not a numeric config key{hint}")
        try:
            start, stop = float(a), float(b)
        except ValueError:
            raise ConfigError(f"--grid {spec!r}: START and STOP must be numbers") from None
        if not (math.isfinite(start) and math.isfinite(stop)):
            raise ConfigError(f"--grid {spec!r}: START and STOP must be finite")
        if not re.fullmatch(r"\d+", n) or int(n) < 1:
            raise ConfigError(f"--grid {spec!r}: COUNT must be a positive integer, got {n!r}")
        count = int(n)
        if count == 1 and start != stop:
            raise ConfigError(f"--grid {spec!r}: COUNT = 1 needs START = STOP")
        if any(ax.key == key for ax in axes):
            raise ConfigError(f"--grid {spec!r}: {key} is swept twice")
        vals = np.linspace(start, stop, count)
        if cfg is not None:  # check the end values alone, with the key's own message
            for v in (start, stop):
                try:
                    apply_values(cfg, {key: v})
                except ConfigError as exc:
                    raise ConfigError(f"--grid {spec!r}: {exc}") from None
        axes.append(Axis(key, vals, spec))
    total = math.prod(len(ax.values) for ax in axes)
    if total > MAX_POINTS:
        raise ConfigError(f"--grid: {total} points is more than {MAX_POINTS}; use fewer points")
    return axes


_KEY = re.compile(r"^([a-z_]+)\.([a-z_0-9]+)(?:\[(\d)\])?$")


def apply_values(cfg: Config, values: dict[str, float]) -> Config:
    """``cfg`` with the given (possibly vector-component) keys set; validated."""
    if not values:
        return cfg
    current = to_dict(cfg)
    sections: dict[str, dict] = {}
    for key, v in values.items():
        section, name, idx = _KEY.match(key).groups()
        sec = sections.setdefault(section, {})
        if idx is None:
            sec[name] = float(v)
        else:
            vec = list(sec.get(name, current[section][name]))
            vec[int(idx)] = float(v)
            sec[name] = vec
    return cfg.replace(**sections)


# -- evaluation -------------------------------------------------------------------------
@dataclass
class SweepResult:
    keys: list[str]
    X: np.ndarray                        # (n, len(keys)) swept values
    shape: tuple                         # grid shape (len of each axis)
    cols: dict = field(default_factory=dict)  # metric name -> array (n,)
    done: np.ndarray = None              # rows computed (False after Ctrl-C)
    seconds: float = 0.0
    interrupted: bool = False
    kernel_seconds: float = 0.0

    @property
    def n(self) -> int:
        return len(self.X)

    @property
    def best(self) -> int | None:
        """Index of the feasible row of least objective (None if none is feasible)."""
        ok = self.cols["feasible"] & self.done
        if not ok.any():
            return None
        J = np.where(ok, self.cols["objective"], np.inf)
        return int(np.argmin(J))

    def row(self, i: int) -> dict:
        d = {k: float(self.X[i, j]) for j, k in enumerate(self.keys)}
        for k in METRICS + ("objective", "feasible", "status", "reason"):
            v = self.cols[k][i]
            if isinstance(v, (np.floating, float)):
                v = None if not np.isfinite(v) else float(v)
            elif isinstance(v, np.bool_):
                v = bool(v)
            d[k] = v
        return d


class _Progress:
    """designs done / total, designs/s and time left on one stderr line (TTY only)."""

    def __init__(self, total: int, enabled: bool):
        self.total, self.enabled, self.t0, self.last = total, enabled, time.perf_counter(), 0.0

    def update(self, done: int, force: bool = False):
        if not self.enabled:
            return
        now = time.perf_counter()
        if not force and now - self.last < 0.2:
            return
        self.last = now
        el = max(now - self.t0, 1e-9)
        rate = done / el
        left = (self.total - done) / rate if rate > 0 else float("inf")
        frac = done / max(self.total, 1)
        bar = "#" * int(30 * frac) + "-" * (30 - int(30 * frac))
        eta = f"{left:5.0f} s left" if math.isfinite(left) else ""
        sys.stderr.write(f"\r  sweep [{bar}] {done}/{self.total}  {rate:,.0f} designs/s  {eta}  ")
        sys.stderr.flush()

    def close(self):
        if self.enabled:
            sys.stderr.write("\n")
            sys.stderr.flush()


def evaluate(cfg: Config, axes: list[Axis], progress: bool = False,
             threads: int | None = None) -> SweepResult:
    """Metrics, objective and feasibility at every grid point (Ctrl-C: partial result)."""
    from .simulate import Simulator
    keys = [ax.key for ax in axes]
    shape = tuple(len(ax.values) for ax in axes)
    mesh = np.meshgrid(*[ax.values for ax in axes], indexing="ij")
    X = np.column_stack([m.ravel() for m in mesh]) if axes else np.zeros((1, 0))
    n = len(X)
    cols = {k: np.full(n, np.nan) for k in METRICS + ("objective", "theta_dot_max")}
    cols["closed"] = np.zeros(n, bool)
    cols["feasible"] = np.zeros(n, bool)
    cols["status"] = np.full(n, "not computed", dtype=object)
    cols["reason"] = np.full(n, "", dtype=object)
    res = SweepResult(keys, X, shape, cols, np.zeros(n, bool))

    d0 = cfg.design
    P = np.tile([d0.spring_k, d0.spring_rest_length, d0.damper_c, d0.rotary_damper_c], (n, 1))
    for j, k in enumerate(keys):
        if k in DESIGN_KEYS:
            P[:, DESIGN_KEYS[k]] = X[:, j]
    other = [j for j, k in enumerate(keys) if k not in DESIGN_KEYS]
    # group rows by their non-design values (model/simulator per group)
    if other:
        G = X[:, other]
        uniq, inv = np.unique(G, axis=0, return_inverse=True)
        inv = inv.ravel()
    else:
        uniq, inv = np.zeros((1, 0)), np.zeros(n, int)
    bar = _Progress(n, progress)
    t0 = time.perf_counter()
    sims: dict = {}
    done = 0
    try:
        order = np.argsort(inv, kind="stable")
        starts = np.searchsorted(inv[order], np.arange(len(uniq) + 1))
        for g in range(len(uniq)):
            rows = order[starts[g]:starts[g + 1]]
            vals = {keys[j]: float(uniq[g, i]) for i, j in enumerate(other)}
            try:
                gcfg = apply_values(cfg, vals)
                # the optimise keys only change feasibility: share the simulator
                skey = tuple(sorted((k, v) for k, v in vals.items()
                                    if not k.startswith("optimise.")))
                if skey not in sims:
                    if len(sims) > 64:
                        sims.clear()
                    sims[skey] = Simulator(gcfg)
                sim = sims[skey]
            except SoftcloseError as exc:
                msg = str(exc).splitlines()[0]
                cols["status"][rows] = "invalid"
                cols["reason"][rows] = msg
                res.done[rows] = True
                done += len(rows)
                bar.update(done)
                continue
            for a in range(0, len(rows), CHUNK):
                r = rows[a:a + CHUNK]
                tk = time.perf_counter()
                out = sim.run_batch(P[r], threads=threads)
                res.kernel_seconds += time.perf_counter() - tk
                _store(res, r, out, gcfg, sim, P[r])
                done += len(r)
                bar.update(done)
    except KeyboardInterrupt:
        res.interrupted = True
    finally:
        bar.update(done, force=True)
        bar.close()
    res.seconds = time.perf_counter() - t0
    return res


def _store(res: SweepResult, rows: np.ndarray, out: dict, cfg: Config, sim, P) -> None:
    from .native import STATUS
    c, o = res.cols, cfg.optimise
    status = out["status"]
    ok = (status == 0) | (status == 1)
    closed = status == 0
    for k in METRICS[1:] + ("theta_dot_max",):
        v = np.asarray(out[k], float).copy()
        if k != "holding_moment":
            v[~ok] = np.nan
        c[k][rows] = v
    c["closed"][rows] = closed
    J = o.weight_impact * out["impact_theta_dot"] ** 2 + o.weight_peak_tip * out["peak_tip_speed"] ** 2
    c["objective"][rows] = np.where(closed, J, np.nan)
    ct, hm = out["closing_time"], out["holding_moment"]
    reason = np.full(len(rows), "", dtype=object)
    # tested in reverse order of REASONS so that the first applicable one is kept
    reason[closed & (out["theta_dot_max"] > 0)] = "rebound"
    reason[hm < o.holding_moment_min] = "not held shut"
    reason[closed & (ct < o.closing_time_min)] = "too fast"
    reason[closed & (ct > o.closing_time_max)] = "too slow"
    reason[~closed] = "not closed"
    st_names = np.array([STATUS.get(int(s), str(s)) for s in range(6)], dtype=object)
    stat = st_names[np.clip(status.astype(int), 0, 5)]
    bad = ~ok
    if bad.any():  # the method could not integrate it: say so, with the remedy
        for i in np.nonzero(bad)[0]:
            s = STATUS.get(int(status[i]), str(status[i]))
            if s == "left the tabulated range":
                reason[i] = "not closed (the lid swung beyond the stroke range)"
            else:
                reason[i] = sim.diagnose(s, P[i])
    c["status"][rows] = stat
    c["reason"][rows] = reason
    c["feasible"][rows] = reason == ""
    res.done[rows] = True


# -- output -----------------------------------------------------------------------------
def write_csv(res: SweepResult, path: Path) -> Path:
    """``sweep.csv``: swept keys, SPEC §4 metrics, objective, feasible, status, reason."""
    header = list(res.keys) + list(METRICS) + ["objective", "feasible", "status", "reason"]
    idx = np.nonzero(res.done)[0]
    num = [res.X[:, j] for j in range(len(res.keys))] + \
          [res.cols[k] for k in METRICS[1:]] + [res.cols["objective"]]

    def f(v):
        return "" if not math.isfinite(v) else repr(float(v))
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        nk = len(res.keys)
        for i in idx:
            vals = [f(a[i]) for a in num]
            w.writerow(vals[:nk] + ["true" if res.cols["closed"][i] else "false"] + vals[nk:]
                       + ["true" if res.cols["feasible"][i] else "false",
                          res.cols["status"][i], res.cols["reason"][i]])
    return path


def read_csv(path: Path) -> dict:
    """Columns of a sweep.csv as arrays (numbers as float, NaN for empty)."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], rows[1:]
    out = {}
    for j, h in enumerate(header):
        col = [r[j] for r in body]
        if h in ("closed", "feasible"):
            out[h] = np.array([v == "true" for v in col])
        elif h in ("status", "reason"):
            out[h] = np.array(col, dtype=object)
        else:
            out[h] = np.array([float(v) if v else np.nan for v in col])
    return out


def _fmt_key(key: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]+", "_", key).strip("_")


def _cells(xs, ys, mask, up: int = 12):
    """``mask`` on grid points, as whole cells (nearest grid point) on a finer grid."""
    def fine(v):
        if len(v) == 1:
            return np.array([v[0]]), np.array([0])
        d = (v[-1] - v[0]) / (len(v) - 1)
        f = np.linspace(v[0] - d / 2, v[-1] + d / 2, up * len(v) + 1)
        return f, np.clip(np.rint((f - v[0]) / d).astype(int), 0, len(v) - 1)
    fx, ix = fine(xs)
    fy, iy = fine(ys)
    XF, YF = np.meshgrid(fx, fy, indexing="ij")
    return XF, YF, mask[np.ix_(ix, iy)].astype(float)


def plot_maps(res: SweepResult, out: Path, max_pairs: int = 15) -> list[Path]:
    """Contour maps over each pair of swept keys (slice through the best feasible point)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from matplotlib.patches import Patch

    files: list[Path] = []
    multi = [j for j, n in enumerate(res.shape) if n >= 2]
    if not multi:
        return files
    best = res.best
    shape = res.shape
    grid = {k: np.reshape(v, shape) for k, v in res.cols.items()}
    done = np.reshape(res.done, shape)
    bidx = np.unravel_index(best, shape) if best is not None else tuple(n // 2 for n in shape)
    axes_vals = [np.linspace(res.X[:, j].min(), res.X[:, j].max(), shape[j])
                 for j in range(len(shape))]
    hatch = {"not closed": None, "too slow": "//", "too fast": "\\\\", "not held shut": "xx",
             "rebound": "..", "invalid": None, "failed": "++"}
    fill = {"not closed": "0.55", "invalid": "0.3"}

    def slc(j1, j2):
        return tuple(slice(None) if j in (j1, j2) else bidx[j] for j in range(len(shape)))

    def classify(reason, status, dn):
        cls = np.full(reason.shape, "", dtype=object)
        for r in ("not closed", "too slow", "too fast", "not held shut", "rebound"):
            cls[np.vectorize(lambda s, r=r: s.startswith(r))(reason)] = r
        cls[(status == "invalid")] = "invalid"
        cls[(reason != "") & (cls == "")] = "failed"
        cls[~dn] = "not computed"
        return cls

    title_fixed = lambda j1, j2: ", ".join(  # noqa: E731
        f"{res.keys[j]} = {axes_vals[j][bidx[j]]:.4g}" for j in range(len(shape))
        if j not in (j1, j2))

    if len(multi) == 1:  # one swept key: profiles
        j = multi[0]
        s = slc(j, j)
        x = axes_vals[j]
        cls = classify(grid["reason"][s], grid["status"][s], done[s])
        fig, axs = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
        for ax, q in zip(axs.ravel(), QUANTITIES):
            y = np.where(cls == "", grid[q][s], np.nan)
            ax.plot(x, grid[q][s], color="0.7", lw=1, label="infeasible")
            ax.plot(x, y, color="C0", lw=2, label="feasible")
            if best is not None:
                ax.plot(x[bidx[j]], grid[q][bidx], "r*", ms=14, label="best feasible")
            name, unit = QUANTITIES[q]
            ax.set_ylabel(f"{name} [{unit}]")
        for ax in axs[1]:
            ax.set_xlabel(label(res.keys[j]))
        axs[0, 0].legend(fontsize=8)
        fig.suptitle(f"Sweep over {res.keys[j]}" + (f" ({title_fixed(j, j)})" if len(shape) > 1 else ""))
        fig.tight_layout()
        p = out / f"profile_{_fmt_key(res.keys[j])}.png"
        fig.savefig(p, dpi=120)
        plt.close(fig)
        return [p]

    pairs = [(a, b) for i, a in enumerate(multi) for b in multi[i + 1:]][:max_pairs]
    for j1, j2 in pairs:
        s = slc(j1, j2)
        xs, ys = axes_vals[j1], axes_vals[j2]
        Xg, Yg = np.meshgrid(xs, ys, indexing="ij")
        if j1 > j2:
            Xg, Yg = Yg, Xg
        cls = classify(grid["reason"][s], grid["status"][s], done[s])
        if j1 > j2:
            cls = cls.T
        feas = cls == ""
        fig, axs = plt.subplots(2, 2, figsize=(11, 8.5), sharex=True, sharey=True)
        present = []
        for ax, q in zip(axs.ravel(), QUANTITIES):
            Z = grid[q][s]
            Z = Z.T if j1 > j2 else Z
            Zm = np.ma.masked_where(~feas | ~np.isfinite(Z), Z)
            name, unit = QUANTITIES[q]
            if Zm.count() >= 1:
                zmin, zmax = float(Zm.min()), float(Zm.max())
                norm = None
                if q == "objective" and zmin > 0 and zmax / zmin > 30:
                    norm = LogNorm(zmin, zmax)
                    levels = np.geomspace(zmin, zmax, 15)
                else:
                    levels = np.linspace(zmin, zmax if zmax > zmin else zmin + 1e-12, 15)
                from matplotlib.colors import BoundaryNorm
                if zmax > zmin:
                    bnorm = BoundaryNorm(levels, 256)
                    if norm is not None:
                        bnorm = BoundaryNorm(levels, 256)
                    # whole cells (nearest grid point): no gap at the feasibility boundary
                    pm = ax.pcolormesh(Xg, Yg, Zm, shading="nearest", cmap="viridis",
                                       norm=bnorm)
                    if Zm.count() >= 4 and min(Zm.shape) >= 3:
                        ax.contour(Xg, Yg, Zm, levels=levels[::2], colors="k",
                                   linewidths=0.4, linestyles="solid")
                    cb = fig.colorbar(pm, ax=ax)
                    if norm is not None:
                        from matplotlib.ticker import FormatStrFormatter
                        cb.set_ticks(np.geomspace(zmin, zmax, 6))
                        cb.ax.yaxis.set_major_formatter(FormatStrFormatter("%.3g"))
                    else:
                        cb.set_ticks(np.linspace(zmin, zmax, 6))
                        cb.ax.yaxis.set_major_formatter(
                            matplotlib.ticker.FormatStrFormatter("%.3g"))
                else:
                    sc = ax.scatter(Xg[feas], Yg[feas], c=Zm.compressed(), cmap="viridis", s=20)
                    cb = fig.colorbar(sc, ax=ax)
                cb.set_label(f"{name} [{unit}]")
            # infeasible regions, by reason
            for r, h in hatch.items():
                m = (cls == r)
                if m.sum() == 0:
                    continue
                if r not in present:
                    present.append(r)
                XF, YF, MF = _cells(Xg[:, 0], Yg[0, :], m)
                ax.contourf(XF, YF, MF, levels=[0.5, 1.5], colors=[fill.get(r, "white")],
                            hatches=[h], alpha=0.85)
                ax.contour(XF, YF, MF, levels=[0.5], colors="0.3", linewidths=0.8)
            if best is not None:
                bx, by = res.X[best, j1], res.X[best, j2]
                if j1 > j2:
                    bx, by = by, bx
                ax.plot(bx, by, marker="*", color="red", mec="white", ms=18, ls="none")
            ax.set_title(name)
        xl, yl = (label(res.keys[j1]), label(res.keys[j2]))
        if j1 > j2:
            xl, yl = yl, xl
        for ax in axs[1]:
            ax.set_xlabel(xl)
        for ax in axs[:, 0]:
            ax.set_ylabel(yl)
        handles = [Patch(facecolor=fill.get(r, "white"), edgecolor="0.3", hatch=hatch[r],
                         label=r) for r in present]
        if best is not None:
            from matplotlib.lines import Line2D
            handles.append(Line2D([], [], marker="*", color="red", mec="white", ms=14, ls="none",
                                  label=f"best feasible (J = {res.cols['objective'][best]:.4g})"))
        fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 6), fontsize=9,
                   frameon=False, bbox_to_anchor=(0.5, -0.01))
        fixed = title_fixed(j1, j2)
        fig.suptitle("Sweep maps; infeasible designs masked (grey or hatched, by reason)"
                     + (f"\nslice at {fixed}" if fixed else ""))
        fig.tight_layout(rect=(0, 0.04, 1, 1))
        p = out / f"map_{_fmt_key(res.keys[j1])}__{_fmt_key(res.keys[j2])}.png"
        fig.savefig(p, dpi=120)
        plt.close(fig)
        files.append(p)
    return files


def sweep(cfg: Config, grid: list[str], out: Path | None = None, progress: bool = False,
          figures: bool = True, threads: int | None = None) -> tuple[SweepResult, list[Path]]:
    """Parse ``grid``, evaluate it and (with ``out``) write sweep.csv and the maps."""
    axes = parse_grid(grid, cfg)
    res = evaluate(cfg, axes, progress=progress, threads=threads)
    files: list[Path] = []
    if out is not None:
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        files.append(write_csv(res, out / "sweep.csv"))
        if figures and not res.interrupted:
            files += plot_maps(res, out)
    return res, files


def summary(res: SweepResult) -> dict:
    c = res.cols
    n_done = int(res.done.sum())
    reasons: dict[str, int] = {}
    for r, dn in zip(c["reason"], res.done):
        if dn and r:
            key = r if r in REASONS else ("invalid" if r and not any(
                r.startswith(x) for x in REASONS) else r.split(" (")[0])
            reasons[key] = reasons.get(key, 0) + 1
    b = res.best
    rate = n_done / res.seconds if res.seconds > 0 else None
    return {"keys": res.keys, "points": res.n, "computed": n_done,
            "feasible": int((c["feasible"] & res.done).sum()),
            "infeasible_reasons": reasons, "interrupted": res.interrupted,
            "seconds": res.seconds, "designs_per_second": rate,
            "best": res.row(b) if b is not None else None}


def command(cfg: Config, args):
    """``softclose sweep --grid KEY=START:STOP:COUNT ... --out DIR``."""
    from .cli.common import Outcome
    progress = (not getattr(args, "json", False)) and sys.stderr.isatty()
    res, files = sweep(cfg, list(args.grid), Path(args.out), progress=progress)
    payload = summary(res)
    payload["files"] = [str(f) for f in files]
    lines = [f"sweep over {', '.join(res.keys)}: {payload['computed']} of {res.n} points in "
             f"{res.seconds:.2f} s ({payload['designs_per_second'] or 0:,.0f} designs/s), "
             f"{payload['feasible']} feasible"]
    if payload["infeasible_reasons"]:
        lines.append("  infeasible: " + ", ".join(f"{k} {v}" for k, v in
                                                    payload["infeasible_reasons"].items()))
    b = payload["best"]
    if b:
        lines.append("  best feasible: " + ", ".join(f"{k} = {b[k]:.6g}" for k in res.keys)
                     + f"  objective {b['objective']:.6g}, closing_time {b['closing_time']:.4f} s, "
                       f"impact {b['impact_theta_dot']:.4f} rad/s, peak tip {b['peak_tip_speed']:.4f} m/s")
    else:
        lines.append("  no feasible point on this grid")
    lines += [f"  wrote {f}" for f in files]
    if res.interrupted:
        lines.append("  interrupted: the rows computed so far are in sweep.csv (no figures)")
        return Outcome(payload, "\n".join(lines), 130, files)
    return Outcome(payload, "\n".join(lines), 0, files)

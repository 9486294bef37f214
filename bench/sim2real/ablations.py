"""The ablation table of bench/sim2real.py: each ablation's AP50 (mean over its seeds) beside the
reference's (``base``: every knob at its default), the difference with its paired bootstrap
interval over the test images, the render's CPU seconds per frame, and a verdict; and the figure
``docs/sim2real.png`` (AP50 against render cost).

Pure functions of the scored rows (:class:`synthgen.evaluate.score.Row`, whose ``ap50_boot``
holds the AP50 of each bootstrap resample). Every model is scored on the same test images with
the same resamples (the draws depend only on the image count, the resample count and the seed),
so the difference of two experiments is bootstrapped *paired*: resample ``b``'s difference is
the difference of the seed-means' AP50 on resample ``b``.

NOTE: the verdict is "no effect" unless both (a) the paired 95% interval of the difference
excludes 0 (image sampling) and (b) the two experiments' seed ranges do not overlap (training
and render seed); otherwise "lower" or "higher" (the ablation against ``base``). Criterion (b)
stands in for a seed-level interval, which 2 seeds cannot give (Efron & Tibshirani 1993, ch. 16:
paired bootstrap over test items; the seed spread is the issue's "differences inside the
intervals are reported as no effect")."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, List, Mapping, Optional, Sequence, Tuple

import numpy as np

__all__ = ["Ablation", "table", "markdown", "figure"]


@dataclass
class Ablation:
    name: str
    ap50: float                         #: mean over the seeds scored (nan: none)
    ap50_ci: Tuple[float, float]        #: bootstrap 95% interval of that mean
    seeds: List[float]                  #: AP50 of each seed's model
    delta: float                        #: ap50 - the reference's (nan for the reference or no model)
    delta_ci: Tuple[float, float]       #: paired bootstrap 95% interval of delta
    cpu_s: float                        #: render CPU seconds per frame (nan: not measured)
    effect: str                         #: "reference", "no effect", "lower", "higher" or "not measured"


def _interval(x: np.ndarray, confidence: float) -> Tuple[float, float]:
    """The central ``confidence`` interval of resamples ``x`` (nan ones left out), as scoring's."""
    from synthgen.evaluate.score import _interval as percentile_interval

    return percentile_interval(x, (1 - confidence) / 2 * 100)


def _mean_boot(rows: Sequence[Any]) -> Optional[np.ndarray]:
    boots = [r.ap50_boot for r in rows if getattr(r, "ap50_boot", None) is not None]
    if len(boots) != len(rows) or not boots or len({len(b) for b in boots}) != 1:
        return None
    return np.mean(np.stack(boots), 0)


def table(rows: Mapping[str, Any], costs: Mapping[str, Mapping[str, float]], names: Sequence[str],
          seeds: Sequence[int], reference: str = "base", confidence: float = 0.95,
          aliases: Optional[Mapping[str, str]] = None) -> List[Ablation]:
    """One :class:`Ablation` per name: ``rows[f"ablation_{name}_s{seed}"]`` are its scored rows
    (missing seeds are left out), ``costs`` the render costs (``frames``, ``cpu_s``) under the
    same keys. ``aliases`` maps a name to the one whose rows and costs it shares (``spp16`` ->
    ``base`` where 16 spp is the default); an alias of the reference is itself a reference."""
    aliases = dict(aliases or {})

    def key(name: str, s: int) -> str:
        return f"ablation_{aliases.get(name, name)}_s{s}"

    def runs(name: str) -> List[Any]:
        return [rows[key(name, s)] for s in seeds if key(name, s) in rows]

    ref = runs(reference)
    ref_boot = _mean_boot(ref)
    ref_seeds = [r.ap50 for r in ref]
    out = []
    for name in names:
        rs = runs(name)
        cs = [costs[key(name, s)] for s in seeds if key(name, s) in costs]
        frames = sum(c["frames"] for c in cs)
        cpu = sum(c["cpu_s"] for c in cs) / frames if frames else math.nan
        vals = [r.ap50 for r in rs]
        boot = _mean_boot(rs)
        ap = float(np.mean(vals)) if vals else math.nan
        ci = _interval(boot, confidence) if boot is not None else (math.nan, math.nan)
        delta, dci, effect = math.nan, (math.nan, math.nan), "not measured"
        if aliases.get(name, name) == reference:
            effect = "reference" if vals else "not measured"
        elif vals and ref_seeds:
            delta = ap - float(np.mean(ref_seeds))
            if boot is not None and ref_boot is not None and len(boot) == len(ref_boot):
                dci = _interval(boot - ref_boot, confidence)
            apart = min(vals) > max(ref_seeds) or max(vals) < min(ref_seeds)
            outside = not math.isnan(dci[0]) and (dci[0] > 0 or dci[1] < 0)
            effect = ("higher" if delta > 0 else "lower") if (apart and outside) else "no effect"
        out.append(Ablation(name, ap, ci, vals, delta, dci, cpu, effect))
    return out


def _f(x: float, sign: bool = False) -> str:
    if x is None or math.isnan(x):
        return "nan"
    return f"{x:+.3f}" if sign else f"{x:.3f}"


def markdown(abl: Sequence[Ablation], knobs: Optional[Mapping[str, str]] = None) -> str:
    """The table as Markdown (one row per ablation, in order)."""
    lines = ["| ablation | changed | AP50 [95%] | seeds | vs base [95%] | effect | render CPU s/frame |",
             "|---|---|---|---|---|---|---|"]
    for a in abl:
        lines.append(f"| `{a.name}` | {(knobs or {}).get(a.name, '')} | {_f(a.ap50)} [{_f(a.ap50_ci[0])}, "
                     f"{_f(a.ap50_ci[1])}] | {', '.join(_f(v) for v in a.seeds) or '-'} | "
                     + ("-" if math.isnan(a.delta) else
                        f"{_f(a.delta, True)} [{_f(a.delta_ci[0], True)}, {_f(a.delta_ci[1], True)}]")
                     + f" | {a.effect} | {_f(a.cpu_s)} |")
    return "\n".join(lines) + "\n"


def figure(abl: Sequence[Ablation], path: str, title: str = "") -> Optional[str]:
    """Writes AP50 (seed mean, bootstrap 95% interval) against render CPU seconds per frame
    (log axis) as the PNG ``path``; ``None`` (nothing written) when no ablation has both."""
    pts = [a for a in abl if not math.isnan(a.ap50) and not math.isnan(a.cpu_s) and a.cpu_s > 0]
    if not pts:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colour = {"reference": "black", "no effect": "tab:gray", "lower": "tab:red", "higher": "tab:green"}
    fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=120)
    for a in pts:
        lo, hi = a.ap50_ci
        err = None if math.isnan(lo) else [[max(0.0, a.ap50 - lo)], [max(0.0, hi - a.ap50)]]
        c = colour.get(a.effect, "tab:blue")
        ax.errorbar([a.cpu_s], [a.ap50], yerr=err, fmt="o", color=c, capsize=3, ms=5)
        ax.annotate(a.name, (a.cpu_s, a.ap50), textcoords="offset points", xytext=(5, 4), fontsize=7, color=c)
    ax.set_xscale("log")
    from matplotlib.ticker import FormatStrFormatter

    ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))   # 4, 6, 10: not 4 x 10^0
    ax.xaxis.set_minor_formatter(FormatStrFormatter("%g"))
    ax.margins(x=0.12)   # room for the rightmost point's name
    ax.set_xlabel("render CPU seconds per frame (log)")
    ax.set_ylabel("car AP50 on the real test frames")
    ax.grid(alpha=0.3, which="both")
    ax.set_title(title or "ablations: AP50 (seed mean, 95% interval) against render cost", fontsize=9)
    handles = [plt.Line2D([], [], color=c, marker="o", ls="", label=k) for k, c in colour.items()]
    ax.legend(handles=handles, fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path

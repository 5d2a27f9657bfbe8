"""The text table of ``simgrip modes``: one line per mode, the chain beside the rod."""

from __future__ import annotations

import math

__all__ = ["format_gripper_modes", "format_modes"]


def _num(x, fmt: str) -> str:
    width = int("".join(ch for ch in fmt.split(".")[0] if ch.isdigit()) or 0)
    return "-".rjust(width) if x is None or not math.isfinite(float(x)) else format(float(x), fmt)


def format_modes(result) -> str:
    """Lines of a :class:`simgrip.modes.ModeResult`: frequency ``omega sqrt(l/g)`` of the chain and of the
    linearised rod, their relative difference (%) and the shapes' MAC, then the settled state."""
    ref = result.reference_frequencies
    lines = [f"grip {result.grip}, {result.links} links, {result.dofs} degrees of freedom; "
             f"omega sqrt(l/g) of the chain and of the linearised rod"]
    lines.append(f"{'mode':>4}  {'chain':>12}  {'rod':>12}  {'diff %':>9}  {'MAC':>10}")
    for k in range(result.count):
        r = None if ref is None else ref[k]
        d = None if result.relative_difference is None else 100.0 * result.relative_difference[k]
        m = None if result.mac is None else result.mac[k]
        lines.append(f"{k + 1:>4}  {_num(result.frequencies[k], '12.6g')}  {_num(r, '12.6g')}  "
                     f"{_num(d, '+9.3g')}  {_num(m, '10.8f')}")
    st = result.settled
    lines.append(f"settled: tip ({st['tip'][0]:.6g}, {st['tip'][1]:.6g}), N1 {st['N1']:.6g}, N2 {st['N2']:.6g}, "
                 f"residual {st['residual']:.3g}, held {st['held']}")
    if ref is None:
        lines.append("no rod reference for this case (two fingers, or a Grip III contact at the tip)")
    return "\n".join(lines)


def format_gripper_modes(rec: dict) -> str:
    """Lines of a K-finger record (:func:`simgrip.modes.gripper.gripper_modes`): the gripper's lowest modes,
    its symmetric ones and the rod's beside them."""
    lines = [f"grip {rec['grip']}, {rec['fingers']} fingers x {rec['links']} links, {rec['workpiece']}, "
             f"{rec['dofs']} degrees of freedom; omega sqrt(l/g)"]
    lines.append(f"{'mode':>4}  {'gripper':>12}  {'symmetric':>12}  {'rod':>12}  {'diff %':>9}")
    ref = rec["reference_frequencies"]
    sym = rec["symmetric_frequencies"]
    for k in range(rec["count"]):
        s = sym[k] if k < len(sym) else None
        r = ref[k] if ref is not None and k < len(ref) else None
        d = rec["relative_difference"][k] if r is not None else None
        lines.append(f"{k + 1:>4}  {_num(rec['frequencies'][k], '12.6g')}  {_num(s, '12.6g')}  {_num(r, '12.6g')}  "
                     f"{_num(None if d is None else 100.0 * d, '+9.3g')}")
    st = rec["settled"]
    lines.append(f"settled: held {st['held']}, residual {st['residual']:.3g}")
    return "\n".join(lines)

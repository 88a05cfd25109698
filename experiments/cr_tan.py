r"""``tan`` correctly rounded almost always, in plain float64 arithmetic: the same bits on every CPU.

An experiment, not part of the package: a candidate for AmigoBot-v0's step's tangent
(:func:`amigo_gym.model.kinematics.col_tan`, numpy's ``tan``), not adopted because compiled it costs more than the
aim (``experiments/portable_tan.py``; docs/architecture.md, "Speed"). Kept here with its test
(``tests/test_plain_tan.py``) as the measured answer to "could the step's tangent be the project's own?". Like
:func:`amigo_gym.model.kinematics.col_exp` it is written once for a Python float, a numpy column and compiled code
(``+ - * /``, selects and a table lookup (:func:`lookup_real`); no C library call, no FMA
contraction), but it evaluates in double-double before its one final rounding, so it gives the correctly rounded
value unless the exact tangent lies extremely close to a rounding midpoint (``tests/test_plain_tan.py``).

- :func:`tan_dd`: relative error about ``2**-100`` before the final rounding.
- :func:`tan_fast`: relative error below about ``2**-65`` and Ziv's rounding test (bound ``2**-62``): its value is
  :func:`tan_dd`'s wherever the test passes (all but about 3 arguments in 1000).
- :func:`tan_cr`: :func:`tan_fast`, then :func:`tan_dd` where its test fails.

Method: ``x = k pi/2 + r`` (``k`` the nearest integer to ``x 2/pi``; ``r`` a double-double from ``pi/2`` in 33-bit
parts, whose products with ``k`` are exact for ``|k| < 2**20``, and a rounded last part), ``r = c + s`` with ``c =
j/64`` and ``|s| <= 1/128``, ``tan s`` by its Taylor series (:func:`tan_dd`: double-double up to the ``s^5`` term),
``tan(c + s) = (T + t) / (1 - T t)`` with ``T = tan c`` from a double-double table (``tests/test_plain_tan.py``
derives it with mpmath), and ``-1 / tan r`` for odd ``k`` by swapping numerator and denominator: one double-double
division. Exact products: :func:`product_error` (Dekker's product; compiled, an FMA, the
same value). ``|x| >= 2**20 pi/2`` (1.647e6 rad, beyond any heading the envs allow, halved), infinities and NaN give
NaN; ``|x| < 2**-27`` gives ``x`` (signed zeros kept).

Imports numpy and :mod:`amigo_gym.model.numeric` only; compiled code registers :data:`SCALAR_FORMS` and
:data:`INTRINSICS` beside numeric's (``tests/test_plain_tan.py``, ``experiments/portable_tan.py``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model.numeric import Real, abs_real, any_real, where_real

__all__ = [
    "tan_cr",
    "tan_dd",
    "tan_fast",
    "quotient_parts",
    "two_sum",
    "two_prod",
    "TAN_LIMIT",
    "SCALAR_FORMS",
    "INTRINSICS",
]


def lookup_float(table: NDArray[np.float64], i: float) -> float:
    """``table[i]`` of a whole number ``i`` held in a float, as a float (:func:`lookup_real`)."""
    return float(table[int(i)])


def lookup_real(table: NDArray[np.float64], i: Real) -> Real:
    """``table[i]`` elementwise, ``i`` whole numbers held in a float or a column (in the table's range: compiled code
    does not check it)."""
    if isinstance(i, np.ndarray):
        out: Real = table[i.astype(np.intp)]
        return out
    return lookup_float(table, i)


def product_error(a: Real, b: Real, p: Real) -> Real:
    """The exact error ``a b - p`` of the rounded product ``p = a * b`` (``|a|, |b| < 2**995``, no underflow), by
    Veltkamp's split of each factor into 26 bits and the rest and Dekker's product; compiled, one fused multiply-add
    ``fma(a, b, -p)``, the same value (:func:`product_error_typing`)."""
    ca = 134217729.0 * a
    ah = ca - (ca - a)
    cb = 134217729.0 * b
    bh = cb - (cb - b)
    al = a - ah
    bl = b - bh
    return ((ah * bh - p) + ah * bl + al * bh) + al * bl


def product_error_typing(typingctx: object, a: Any, b: Any, p: Any) -> Any:
    """The typing and code of :func:`product_error` on floats in compiled code (numba's ``intrinsic``, registered in
    its place like :func:`pow2_typing`): ``llvm.fma(a, b, -p)``, exact as Dekker's product is (an FMA instruction
    where the CPU has one, else the C library's ``fma``, correctly rounded too)."""
    from numba.core import types

    if not all(isinstance(v, types.Float) for v in (a, b, p)):
        return None

    def codegen(context: object, builder: Any, signature: object, values: list[Any]) -> Any:
        return builder.fma(values[0], values[1], builder.fneg(values[2]))

    return types.float64(a, b, p), codegen


#: ``|x|`` from which :func:`tan_dd` gives NaN: ``2**20 pi/2`` (``k * P`` of a 33-bit part ``P`` exact below)
TAN_LIMIT = 1647099.3291652855
#: ``1.5 * 2**52``: ``(t + _ROUND) - _ROUND`` rounds a float below ``2**51`` in magnitude to an integer
_ROUND = 6755399441055744.0
_TWO_OVER_PI = 0.6366197723675814
#: ``pi/2`` in four parts of 33 bits and a fifth (error below ``3e-60``)
_P1, _P2, _P3, _P4, _P5 = (1.5707963267341256, 6.077100506303966e-11, 2.0222662487111665e-21, 8.478427660348229e-32,
                           2.0670321098263988e-43)  # fmt: skip
#: ``1/3`` and ``2/15`` as double-doubles, then the series' next coefficients ``17/315 ... 21844/6081075``
_C1, _C1L, _C2, _C2L = 0.3333333333333333, 1.850371707708594e-17, 0.13333333333333333, 1.8503717077085942e-18
_C3, _C4, _C5, _C6 = 0.05396825396825397, 0.021869488536155203, 0.008863235529902197, 0.003592128036572481
#: ``tan(j / 64)`` for ``j = 0 ... 50`` as double-doubles (high and low parts), rounded to nearest from mpmath
_TAN_HI = (
    0.0, 0.015626271689943825, 0.031260176501255954, 0.04690936247710255, 0.06258150756627502, 0.07828433473151954,
    0.09402562724573195, 0.1098132442407294, 0.12565513657513097, 0.14155936309019246, 0.15753410732527162,
    0.17358769476798153, 0.18972861071805913, 0.20596551884857886, 0.22230728055343132, 0.23876297517602593,
    0.25534192122103627, 0.2720536986587709, 0.2889081724405147, 0.3059155173530593, 0.32308624435174554,
    0.3404312285238304, 0.357961738848017, 0.37568946993175484, 0.39362657592563277, 0.4117857068341085,
    0.43018004746423005, 0.4488233592792397, 0.4677300254523918, 0.48691509944840633, 0.5063943574962299,
    0.5261843553577792, 0.5463024898437905, 0.5667670655805864, 0.5875973675914432, 0.6088137403243807,
    0.6304376738358848, 0.652491897928808, 0.6750004851442429, 0.6979889636235993, 0.7214844409909045,
    0.745515740559392, 0.7701135513442087, 0.7953105935686742, 0.8211418015898941, 0.8476445264465526,
    0.8748587605544823, 0.9028273874526735, 0.9315964599440725, 0.9612155104943704, 0.9917378983632686,
)  # fmt: skip
_TAN_LO = (
    0.0, -1.1098581353360207e-18, 2.3803927834128917e-18, 1.0758096521931646e-18, -6.767531942779112e-18,
    6.549354523305424e-18, 6.5762523927164225e-18, -1.3618676618888177e-18, -3.439960680352485e-18,
    -1.3524814290822953e-18, -1.1061539275293055e-17, -5.466799905601509e-18, 9.78955701743985e-19,
    1.1941630400622213e-17, 6.328821377607695e-18, -1.1965363417854254e-17, -5.589358343564783e-18,
    1.7800462751146556e-18, 2.70817328270223e-17, -1.0067614575865017e-17, -2.389398809095344e-17,
    -1.0685631122211716e-17, -2.086600346579411e-17, 2.3479794206893734e-18, -1.2972931096830582e-17,
    -2.2916307323113633e-18, -4.113275164307763e-18, -1.0902959500750133e-17, 1.5519502793263498e-17,
    -5.4529487901411026e-18, -4.0096068550680074e-17, -4.348570622585069e-17, 2.9096576216837176e-17,
    1.9081591885745848e-17, 1.211599079372634e-17, -1.5211272122785565e-17, -1.5183875765700744e-17,
    -2.5135228075258745e-17, -2.666904806431612e-17, -4.597285845994556e-17, -5.4243984813454325e-17,
    3.562842334947556e-17, 3.6147512759166313e-17, 1.2219754107307511e-17, -1.6135619305114956e-17,
    1.6624363269060354e-17, 4.305785584054271e-17, -4.4323402665013125e-17, -1.3547381396593036e-17,
    4.3011833411291044e-17, 3.625934281680031e-17,
)  # fmt: skip
#: the tables for ``j = -50 ... 50`` (``tan`` is odd), indexed by ``j + 50``
_T_HI = np.array([-t for t in _TAN_HI[:0:-1]] + list(_TAN_HI))
_T_LO = np.array([-t for t in _TAN_LO[:0:-1]] + list(_TAN_LO))


def two_sum(a: Real, b: Real) -> tuple[Real, Real]:
    """``(s, e)``: ``s = a + b`` rounded and its exact error, ``a + b = s + e`` (Knuth)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def two_prod(a: Real, b: Real) -> tuple[Real, Real]:
    """``(p, e)``: ``p = a b`` rounded and its exact error, ``a b = p + e``
    (:func:`product_error`: Dekker's product, an FMA compiled)."""
    p = a * b
    return p, product_error(a, b, p)


#: ``pi/2 - P1 - P2`` rounded (the fast path's third part)
_P3R = 2.0222662487959506e-21


def quotient_parts(k: Real, j: Real, th: Real, tl: Real) -> tuple[Real, Real, Real, Real]:
    """``tan(c + s) = (T + t) / (1 - T t)`` (``-1 / tan(c + s)`` for odd ``k``) as the double-double numerator
    ``(uh, ul)`` and denominator ``(bh, bl)``: ``T = tan(j / 64)`` from the table, ``t = th + tl``."""
    i = where_real(abs_real(j) <= 50.0, j, 0.0) + 50.0  # in the table for NaN and large x too
    big, small = lookup_real(_T_HI, i), lookup_real(_T_LO, i)
    nh, nl = two_sum(big, th)
    nl = nl + (small + tl)
    ph, pl = two_prod(big, th)
    dh = 1.0 - ph
    dl = (((1.0 - dh) - ph) - pl) - (big * tl + small * th)
    odd = k != 2.0 * ((0.5 * k + _ROUND) - _ROUND)
    return where_real(odd, -dh, nh), where_real(odd, -dl, nl), where_real(odd, nh, dh), where_real(odd, nl, dl)


def tan_fast(x: Real) -> tuple[Real, bool | NDArray[np.bool_]]:
    """``(y, bad)``: ``tan(x)`` correctly rounded where ``bad`` is false (about 999 arguments in 1000), from a
    double-double of relative error below about ``2**-65`` and Ziv's rounding test with the bound ``2**-62``."""
    k = (x * _TWO_OVER_PI + _ROUND) - _ROUND
    rh, rl = two_sum(x - k * _P1, -(k * _P2))
    rl = rl - k * _P3R
    j = (rh * 64.0 + _ROUND) - _ROUND
    sh = rh - j * 0.015625
    z = sh * sh
    th, tl = two_sum(sh, rl + (rl * z + sh * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * _C5))))))
    a = abs_real(x)
    uh, ul, bh, bl = quotient_parts(k, j, th, tl)
    q = uh / bh
    ph, pl = two_prod(q, bh)
    ql = (((uh - ph) - pl) + ul - q * bl) / bh
    eps = abs_real(q) * 2.168404344971009e-19
    y = q + ql
    bad = (q + (ql - eps)) != (q + (ql + eps))
    bad = bad | ((k != 0.0) & (abs_real(rh) < 1.4901161193847656e-08))
    return where_real(a < 7.450580596923828e-09, x, where_real(a < TAN_LIMIT, y, np.nan)), bad


def tan_dd(x: Real) -> Real:
    """``tan(x)`` correctly rounded almost always, for a float, a column or compiled (the module's docstring)."""
    k = (x * _TWO_OVER_PI + _ROUND) - _ROUND
    # r = x - k pi/2 as a double-double: x - k P1 exact (Sterbenz), the exact errors of the next two summed apart
    s, e = two_sum(x - k * _P1, -(k * _P2))
    s, e3 = two_sum(s, -(k * _P3))
    s, e4 = two_sum(s, -(k * _P4))
    lo = ((e + e3) + e4) - k * _P5
    rh = s + lo
    rl = (s - rh) + lo
    # r = j/64 + s, |s| <= 1/128; t = tan(s) = s + s z (1/3 + z (2/15 + z (17/315 + ...))), z = s^2
    j = (rh * 64.0 + _ROUND) - _ROUND
    sh, sl = two_sum(rh - j * 0.015625, rl)
    zh, zl = two_prod(sh, sh)
    zl = zl + 2.0 * sh * sl
    eh, el = two_sum(_C2, zh * (_C3 + zh * (_C4 + zh * (_C5 + zh * _C6))))
    ph, pl = two_prod(zh, eh)
    ch, cl = two_sum(_C1, ph)
    cl = cl + ((pl + zh * (el + _C2L) + zl * eh) + _C1L)
    wh, wl = two_prod(zh, ch)
    wl = wl + zh * cl + zl * ch
    vh, vl = two_prod(sh, wh)
    th, tl = two_sum(sh, vh)
    tl = tl + (sl + ((vl + sh * wl) + sl * wh))
    # tan(c + s) = (T + t) / (1 - T t); -1 / tan(c + s) for odd k
    a = abs_real(x)
    uh, ul, bh, bl = quotient_parts(k, j, th, tl)
    q = uh / bh
    ph, pl = two_prod(q, bh)
    y = q + ((((uh - ph) - pl) + ul) - q * bl) / bh
    return where_real(a < 7.450580596923828e-09, x, where_real(a < TAN_LIMIT, y, np.nan))


def tan_cr(x: Real) -> Real:
    """:func:`tan_fast`'s value, :func:`tan_dd`'s where its rounding test fails: the same bits as :func:`tan_dd`."""
    y, bad = tan_fast(x)
    if any_real(bad):
        y = where_real(bad, tan_dd(x), y)
    return y


#: what compiled code must register besides :data:`amigo_gym.model.numeric.SCALAR_FORMS` (with
#: :func:`amigo_gym.sim.layout.shared_compiler`): the table lookup's float form, and the exact product's FMA
SCALAR_FORMS = {lookup_real: lookup_float}
INTRINSICS = {product_error: product_error_typing}

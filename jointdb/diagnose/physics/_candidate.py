"""What a candidate physics is: its parameters, the context it is offered in, the
base class and the pairing of two, and the registry of factories (see the package
docstring for how to add one)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

__all__ = ["Param", "Context", "Candidate", "Combination", "register", "candidates_for", "REGISTRY", "IDENTIFIED"]

#: A parameter counts as identified when its reported 1σ (statistical and model-form) is at most this
#: fraction of its value; beyond it the value is shown as "not resolved" and, for a key parameter, the
#: candidate is not named (see :mod:`jointdb.diagnose._identify`).
IDENTIFIED = 0.5


@dataclass(frozen=True)
class Param:
    """A fitted parameter of a candidate physics.

    Parameters
    ----------
    name
        The parameter's name (e.g. ``"mass"``).
    unit
        Its SI unit (e.g. ``"kg"``).
    lower, upper
        Bounds of the fit, SI.
    start
        Starting value, SI.
    log
        Fitted in log space (positive parameters spanning decades).
    show, show_unit
        Display factor and unit (e.g. ``show=1e3, show_unit="g"``).
    starts
        Extra starting values for multi-start fits, SI.
    plausible
        The physically plausible range (default: the fit bounds); a fitted value outside it
        is reported and penalised (:meth:`implausibility`).
    equivalent
        The value is that of an equivalent (lumped) model, not a measurable property of the part:
        reported as "equivalent <name>" (e.g. a contact's length over which a uniform layer does
        what the real, non-uniform pressure does).
    key
        A key parameter must be identified (σ ≤ ``IDENTIFIED`` × value) for the candidate to be named.
    either
        Key parameters sharing a non-empty ``either`` group need only one of them identified (a joint
        stiff in translation but compliant in rotation is identified by its rotational stiffness).
    """

    name: str
    unit: str
    lower: float
    upper: float
    start: float
    log: bool = True
    show: float = 1.0
    show_unit: str = ""
    starts: tuple[float, ...] = ()
    plausible: tuple[float, float] | None = None
    #: the value is that of an equivalent (lumped) model, not a measurable property of the part: it is
    #: reported as "equivalent <name>" (e.g. a contact's length over which a uniform layer does what the
    #: real, non-uniform pressure does)
    equivalent: bool = False
    #: a key parameter must be identified (σ ≤ IDENTIFIED × value) for the candidate to be named;
    #: key parameters sharing a non-empty ``either`` group need only one of them identified (a joint
    #: stiff in translation but compliant in rotation is identified by its rotational stiffness)
    key: bool = True
    either: str = ""

    def implausibility(self, value: float) -> float:
        """Distance of ``value`` outside the plausible range, in units of that range's width
        (in log space for logarithmic parameters); 0 inside.

        Parameters
        ----------
        value
            A value of the parameter, SI.

        Returns
        -------
        float
        """
        if self.plausible is None:
            return 0.0
        lo, hi = self.plausible
        if self.log and lo > 0 and value > 0:
            x, a, b = np.log(value), np.log(lo), np.log(hi)
        else:
            x, a, b = value, lo, hi
        width = max(b - a, 1e-12)
        return float(max(a - x, x - b, 0.0) / width)

    @property
    def label(self) -> str:
        """The name as the verdict shows it (``equivalent insertion`` for an equivalent model's value)."""
        return f"equivalent {self.name}" if self.equivalent else self.name

    def shown(self, value: float, sigma: float | None) -> str:
        """``name = value ± σ unit``, or ``name ≈ value unit (not resolved …)`` when σ > IDENTIFIED × value.

        Parameters
        ----------
        value
            The fitted value, SI.
        sigma
            Its standard deviation, SI, or None.

        Returns
        -------
        str
            One line of the verdict.
        """
        if sigma is not None and self.relative_sigma(value, sigma) > IDENTIFIED:
            return f"{self.label} ≈ {self.fmt(value)} (not resolved by these measurements)"
        return f"{self.label} = {self.fmt(value, sigma)}"

    def relative_sigma(self, value: float, sigma: float | None) -> float:
        """σ / |value| (inf when σ is unknown or the value is 0).

        Parameters
        ----------
        value, sigma
            As :meth:`shown`.

        Returns
        -------
        float
            Compared with ``IDENTIFIED`` to decide whether the value is resolved.
        """
        if sigma is None or not np.isfinite(sigma) or value == 0:
            return float("inf")
        return float(abs(sigma) / abs(value))

    def to_u(self, value: float) -> float:
        """The optimiser's coordinate of a value (``log(value/start)``, or scaled offset).

        Parameters
        ----------
        value
            A value of the parameter, SI.

        Returns
        -------
        float
        """
        return float(np.log(value / self.start)) if self.log else (value - self.start) / self.scale

    def from_u(self, u: float) -> float:
        """The value of an optimiser coordinate (inverse of :meth:`to_u`).

        Parameters
        ----------
        u
            The optimiser's coordinate.

        Returns
        -------
        float
            The value, SI.
        """
        return float(self.start * np.exp(u)) if self.log else float(self.start + u * self.scale)

    @property
    def scale(self) -> float:
        return (self.upper - self.lower) / 10.0

    @property
    def u_bounds(self) -> tuple[float, float]:
        return self.to_u(self.lower), self.to_u(self.upper)

    def fmt(self, value: float, sigma: float | None = None) -> str:
        """The value (± sigma) for display, e.g. ``"5.6 ± 0.3 g"``.

        Parameters
        ----------
        value
            The value, SI.
        sigma
            Its standard deviation, SI, or None.

        Returns
        -------
        str
        """
        unit = self.show_unit or self.unit
        unit = "" if unit == "-" else unit
        v = value * self.show
        if sigma is None or not np.isfinite(sigma):
            return f"{v:.3g} {unit}".strip()
        return f"{v:.3g} ± {sigma * self.show:.2g} {unit}".strip()


@dataclass(frozen=True, eq=False)
class Context:
    """What candidates need to know: the nominal model, measured points, levels.

    Parameters
    ----------
    model
        The nominal :class:`jointdb.fe.BeamModel`.
    points
        The model points the recordings are at.
    n_levels
        Number of excitation levels recorded.
    levels
        The levels (None where not given).
    modes_hz
        The nominal model's natural frequencies [Hz].
    """

    model: object
    points: tuple[str, ...]
    n_levels: int
    levels: tuple
    modes_hz: np.ndarray


class Candidate:
    """Base class of one candidate physics (see the package docstring)."""

    name: str = ""
    family: str = ""
    slot: str = ""               # candidates sharing a slot cannot be combined
    explanation: str = ""
    params: tuple[Param, ...] = ()
    per_level: bool = False

    def apply(self, model, values: dict, level: int = 0):
        """The nominal model with this physics added.

        Parameters
        ----------
        model
            The nominal :class:`jointdb.fe.BeamModel`.
        values
            Parameter name → value, SI.
        level
            Index of the excitation level (for level-dependent physics).

        Returns
        -------
        BeamModel
            The base class returns ``model`` unchanged.
        """
        return model

    def chain(self, freq: np.ndarray, values: dict, level: int = 0):
        """A factor on the model FRF from the measurement chain (gain, delay), or None.

        Parameters
        ----------
        freq
            Frequency lines [Hz], ``(n_freq,)``.
        values
            Parameter name → value, SI.
        level
            Index of the excitation level.

        Returns
        -------
        ndarray or None
            Complex factor ``(n_freq,)``; the base class returns None (no chain effect).
        """
        return None

    def describe(self, values: dict, sigmas: dict | None = None) -> str:
        """Plain-language phrase with the fitted values, e.g. 'an unmodelled 5.6 ± 0.3 g sensor at tip'.

        Parameters
        ----------
        values
            Parameter name → fitted value, SI.
        sigmas
            Parameter name → standard deviation, SI, or None.

        Returns
        -------
        str
        """
        parts = ", ".join(p.shown(values[p.name], (sigmas or {}).get(p.name)) for p in self.params)
        return f"{self.explanation} ({parts})" if parts else self.explanation

    def __repr__(self) -> str:
        return f"<candidate {self.name}>"


class Combination(Candidate):
    """Two candidates applied together (parameters prefixed ``a.``/``b.``)."""

    def __init__(self, first: Candidate, second: Candidate):
        self.parts = (first, second)
        self.name = f"{first.name} + {second.name}"
        self.family = f"{first.family} + {second.family}"
        self.slot = ""
        self.explanation = f"{first.explanation}; and {second.explanation}"
        self.per_level = first.per_level or second.per_level
        self.params = tuple(dataclasses.replace(p, name=f"{k}.{p.name}")
                            for k, c in zip("ab", self.parts) for p in c.params)

    def _split(self, values):
        return [{p.name: values[f"{k}.{p.name}"] for p in c.params} for k, c in zip("ab", self.parts)]

    def apply(self, model, values, level=0):
        # candidates that move the model's coordinates (e.g. an insertion prepended) go last
        todo = sorted(zip(self.parts, self._split(values)), key=lambda cv: bool(getattr(cv[0], "reshapes", False)))
        for c, v in todo:
            model = c.apply(model, v, level)
        return model

    def chain(self, freq, values, level=0):
        out = None
        for c, v in zip(self.parts, self._split(values)):
            f = c.chain(freq, v, level)
            if f is not None:
                out = f if out is None else out * f
        return out

    def describe(self, values, sigmas=None):
        sigmas = sigmas or {}
        texts = []
        for k, c, v in zip("ab", self.parts, self._split(values)):
            s = {p.name: sigmas[f"{k}.{p.name}"] for p in c.params if f"{k}.{p.name}" in sigmas}
            texts.append(c.describe(v, s))
        return " together with ".join(texts)


REGISTRY: list[Callable[[Context], Iterable[Candidate]]] = []


def register(factory: Callable[[Context], Iterable[Candidate]]):
    """Decorator: add a candidate factory ``f(context) -> iterable of Candidate``.

    Parameters
    ----------
    factory
        Called with a :class:`Context` for every diagnosis.

    Returns
    -------
    callable
        ``factory`` itself.
    """
    REGISTRY.append(factory)
    return factory


def candidates_for(ctx: Context) -> list[Candidate]:
    """All candidates the registered factories offer for this model and data.

    Parameters
    ----------
    ctx
        The :class:`Context`.

    Returns
    -------
    list of Candidate
    """
    out: list[Candidate] = []
    for factory in REGISTRY:
        out.extend(factory(ctx))
    return out

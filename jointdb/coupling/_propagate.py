"""Carry a joint's parameter uncertainty to a coupled prediction by ensemble propagation.

A joint identified by output error comes with its fitted parameters θ and their covariance
(``jointdb-joint-uncertainty/1`` records, see :func:`uncertainty_record`). Samples
``θ_s ~ N(θ, Σ)`` give plausible joints; each is coupled, all samples at once (the sample
axis is stacked onto the frequency axis, so one batched solve serves the ensemble), and
percentiles over the samples give a band.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from jointdb.errors import InputError

__all__ = ["uncertainty_record", "sample_theta", "spring_damper_samples", "band", "ensemble_coupled"]

FORMAT = "jointdb-joint-uncertainty/1"


def uncertainty_record(fit) -> dict:
    """The JSON-able uncertainty of an :class:`~jointdb.coupling.OutputErrorResult`.

    Keys: ``format``, ``model`` (``spring-damper`` or ``joint-body``), ``names``, ``theta``,
    ``covariance`` (of θ as optimised: natural logs of k and c for spring–dampers,
    ``theta_is_log``), ``dofs`` (joint DOF labels), ``order``, ``residual_rms``.
    """
    rec = {
        "format": FORMAT,
        "model": "spring-damper" if fit.log_parameters else "joint-body",
        "names": list(fit.names),
        "theta": [float(x) for x in fit.theta],
        "covariance": [[float(x) for x in row] for row in fit.covariance],
        "theta_is_log": bool(fit.log_parameters),
        "dofs": [str(d) for d in fit.model.labels],
        "residual_rms": float(fit.residual_rms),
    }
    if fit.log_parameters:
        rec["order"] = int(fit.model.order)
    return rec


def _check(record: Mapping) -> tuple[np.ndarray, np.ndarray]:
    if not isinstance(record, Mapping) or record.get("format") != FORMAT:
        raise InputError(f"not a joint uncertainty record (format {FORMAT!r} expected)")
    theta = np.asarray(record["theta"], float)
    cov = np.asarray(record["covariance"], float)
    if cov.shape != (theta.size, theta.size) or not np.all(np.isfinite(cov)):
        raise InputError(f"joint uncertainty: covariance has shape {cov.shape}, theta {theta.size} values")
    return theta, cov


def sample_theta(record: Mapping, n: int, seed: int | None = 0) -> np.ndarray:
    """``n`` draws of θ from ``N(theta, covariance)``, shape ``(n, p)`` (covariance may be singular)."""
    theta, cov = _check(record)
    w, v = np.linalg.eigh((cov + cov.T) / 2)
    root = v * np.sqrt(np.clip(w, 0, None))
    z = np.random.default_rng(seed).standard_normal((int(n), theta.size))
    return theta[None, :] + z @ root.T


def spring_damper_samples(record: Mapping, freq: np.ndarray, n: int, seed: int | None = 0,
                          thetas: np.ndarray | None = None) -> np.ndarray:
    """Sampled spring–damper joint receptances, diagonal, shape ``(n, n_freq, m, m)`` for m joint DOFs.

    Raises
    ------
    InputError
        A record that is not a spring–damper model.
    """
    if record.get("model") != "spring-damper":
        raise InputError(f"joint uncertainty of model {record.get('model')!r}: only spring-damper joints are sampled")
    from jointdb.coupling._oe_core import SpringDamperModel
    from jointdb.frf import dofs

    model = SpringDamperModel(dofs(record["dofs"]), int(record.get("order", 0)))
    th = sample_theta(record, n, seed) if thetas is None else np.asarray(thetas, float)
    freq = np.asarray(freq, float)
    m = len(model.labels)
    basis = np.polynomial.legendre.legvander(2 * (freq - freq[0]) / max(freq[-1] - freq[0], 1e-300) - 1, model.order)
    t = th.reshape(th.shape[0], m, 2, model.order + 1)
    k = np.exp(np.einsum("fl,sjl->sfj", basis, t[:, :, 0, :]))
    c = np.exp(np.einsum("fl,sjl->sfj", basis, t[:, :, 1, :]))
    z = k + 1j * (2 * np.pi * freq)[None, :, None] * c
    out = np.zeros((th.shape[0], freq.size, m, m), complex)
    idx = np.arange(m)
    out[:, :, idx, idx] = 1.0 / z
    return out


def band(samples: np.ndarray, quantiles: Sequence[float] = (0.05, 0.5, 0.95), axis: int = 0) -> np.ndarray:
    """Percentiles over the sample axis (NaN-aware), stacked first: shape ``(len(quantiles), ...)``."""
    return np.nanquantile(samples, quantiles, axis=axis)


def ensemble_coupled(blocks, z_samples: np.ndarray) -> np.ndarray:
    """Coupled FRFs of :class:`~jointdb.coupling._oe_core.CoupledBlocks` for sampled joint stiffnesses.

    Parameters
    ----------
    blocks
        θ-independent blocks (nf lines, nc contact DOFs).
    z_samples
        Joint dynamic stiffness over the contact DOFs per sample, ``(n, nf, nc, nc)``.

    Returns
    -------
    ndarray ``(n, nf, no, ni)``
    """
    n, nf = z_samples.shape[:2]

    def tile(a):
        return np.broadcast_to(a, (n,) + a.shape).reshape((n * nf,) + a.shape[1:])

    from jointdb.coupling._oe_core import CoupledBlocks

    big = CoupledBlocks(np.tile(blocks.freq, n), tile(blocks.h_oi), tile(blocks.u), tile(blocks.v),
                        tile(blocks.h_cc), blocks.outputs, blocks.inputs, blocks.n_a)
    g = big.coupled(z_samples.reshape((n * nf,) + z_samples.shape[2:]))
    return g.reshape((n, nf) + g.shape[1:])


def spring_pairs_stiffness(joint_receptance_samples: np.ndarray) -> np.ndarray:
    """Dynamic stiffness over ``a_dofs + b_dofs`` of diagonal spring–damper samples ``(n, nf, m, m)``."""
    n, nf, m, _ = joint_receptance_samples.shape
    z = 1.0 / np.diagonal(joint_receptance_samples, axis1=2, axis2=3)  # (n, nf, m)
    d = np.zeros((2 * m, m))
    d[np.arange(m), np.arange(m)] = 1.0
    d[m + np.arange(m), np.arange(m)] = -1.0
    return np.einsum("cj,sfj,dj->sfcd", d, z, d)

"""equilibrated_pinvs over blocks of different sizes (issue 23: found while splitting it).

The extreme eigenvalues of each size's Gram matrices were computed with the scales of the
last size built, which raised (or mis-scaled) as soon as a side had blocks of two sizes.
"""

import numpy as np

from jointdb.coupling._linalg import equilibrated_pinvs


def _blocks(rng, nf, shapes):
    out = [rng.normal(size=(nf, *s)) + 1j * rng.normal(size=(nf, *s)) for s in shapes]
    out[0][:, 0] *= 1e3  # mixed units: the equilibration matters
    return out


def _reference(blocks, nf):
    rows = np.cumsum([0] + [b.shape[1] for b in blocks])
    cols = np.cumsum([0] + [b.shape[2] for b in blocks])
    whole = np.zeros((nf, rows[-1], cols[-1]), dtype=complex)
    for k, b in enumerate(blocks):
        whole[:, rows[k]:rows[k + 1], cols[k]:cols[k + 1]] = b
    p = np.linalg.pinv(whole)
    return [p[:, cols[k]:cols[k + 1], rows[k]:rows[k + 1]] for k in range(len(blocks))]


def test_wide_and_tall_sides_with_blocks_of_two_sizes_match_the_pseudo_inverse():
    rng = np.random.default_rng(3)
    nf = 40
    wide = _blocks(rng, nf, [(3, 6), (5, 6)])     # Gram matrices 3×3 and 5×5
    tall = _blocks(rng, nf, [(6, 2), (6, 4)])     # Gram matrices 2×2 and 4×4
    (pw, cw), (pt, ct) = equilibrated_pinvs([(wide, True), (tall, False)])
    for got, want in zip(pw + pt, _reference(wide, nf) + _reference(tall, nf)):
        assert np.max(np.abs(got - want)) <= 1e-10 * np.max(np.abs(want))
    assert np.all(np.isfinite(cw)) and np.all(np.isfinite(ct))

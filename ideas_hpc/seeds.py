"""The seed scheme: one random stream per campaign sample (SPEC section 8).

Sample ``k`` of a campaign with seed ``s`` draws from
``np.random.default_rng(np.random.SeedSequence(s, spawn_key=(k,)))``, the same
stream as ``SeedSequence(s).spawn(k + 1)[k]`` (numpy's documented children),
so any sample re-runs alone and results depend neither on chunking nor on the
worker count. A sample that needs independent streams for separate purposes
takes children of its own sequence, ``spawn_key=(k, c)`` (e.g. the Monte Carlo
dispersions use ``c = 1`` while the attitude initial conditions use the
sample's own stream).

Stores keep ``s`` in their attrs and, per sample, the first :data:`SEED_WORDS`
words of the sample's sequence state (:func:`seeds_for`), which identify it.
"""

from __future__ import annotations

import numpy as np

from .errors import InputError

#: Words of a sample's SeedSequence state kept in stores (``sample_seed``).
SEED_WORDS = 4


def sample_seed_sequence(campaign_seed: int, k: int, *child: int) -> np.random.SeedSequence:
    """``SeedSequence(campaign_seed, spawn_key=(k, *child))``: sample ``k`` or its child."""
    return np.random.SeedSequence(int(campaign_seed),
                                  spawn_key=(int(k),) + tuple(int(c) for c in child))


def sample_rng(campaign_seed: int, k: int, *child: int) -> np.random.Generator:
    """Random generator of sample ``k`` (or of its child), see :func:`sample_seed_sequence`."""
    return np.random.default_rng(sample_seed_sequence(campaign_seed, k, *child))


def seeds_for(campaign_seed: int, n_samples: int) -> np.ndarray:
    """Per-sample seed words, ``(n_samples, SEED_WORDS)`` uint32.

    Row ``k`` is ``SeedSequence(campaign_seed, spawn_key=(k,)).generate_state(4)``;
    it identifies the stream :func:`sample_rng` gives for sample ``k``.
    """
    if int(n_samples) < 0:
        raise InputError(f"must be >= 0, got {n_samples}", field="n_samples")
    out = np.empty((int(n_samples), SEED_WORDS), dtype=np.uint32)
    for k in range(int(n_samples)):
        out[k] = sample_seed_sequence(campaign_seed, k).generate_state(SEED_WORDS, np.uint32)
    return out

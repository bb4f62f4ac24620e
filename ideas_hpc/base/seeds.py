"""The seed scheme: one random stream per campaign sample (SPEC section 8).

Sample ``k`` of a campaign with seed ``s`` draws from
``np.random.default_rng(np.random.SeedSequence(s, spawn_key=(k,)))``, the same
stream as ``SeedSequence(s).spawn(k + 1)[k]`` (numpy's documented children),
so any sample re-runs alone and results depend neither on chunking nor on the
worker count. A sample that needs independent streams for separate purposes
takes children of its own sequence, ``spawn_key=(k, c)`` (e.g. the Monte Carlo
dispersions use ``c = 1`` while the attitude initial conditions use the
sample's own stream).

Design streams (issue 20)
-------------------------
The reliability designer draws from two more families, keyed by three words
so that they can never be a Monte Carlo sample's key (one word, ``(k,)``) or
a sample child's (two words, ``(k, c)``)::

    scenario s of the scenario bank:     SeedSequence(seed, spawn_key=(SCENARIO_STREAM, s, c))
    validation sample m of a design:     SeedSequence(seed, spawn_key=(VALIDATION_STREAM, m, c))

``c`` selects the purpose (:data:`STREAM_BODY`: gravity and reflectivity,
shared by all spacecraft; :data:`STREAM_SPACECRAFT`: initial state errors and
misalignment, one independent draw per spacecraft; :data:`STREAM_ATTITUDE`:
the initial attitude, rates and wheel speeds per spacecraft). The two stream
words differ, so the scenario and validation families share no sequence
(:func:`stream_seed_sequence`); stores record both words.

Target worlds (issue 42)
------------------------
A world of the target prior and its navigation errors draw from two more families,
keyed by four words (so never a sample's, a sample child's or a design stream's key)::

    part c of world k:        SeedSequence(seed, spawn_key=(WORLD_STREAM, family, k, c))
    navigation m of world k:  SeedSequence(seed, spawn_key=(NAVIGATION_STREAM, family, k, m))

``c`` is :data:`WORLD_SHAPE`, :data:`WORLD_SIZE`, :data:`WORLD_POLE` or
:data:`WORLD_ROTATION`; ``family`` is 0, or :data:`SCENARIO_STREAM` /
:data:`VALIDATION_STREAM` to keep the bank's worlds and fresh validation worlds apart
(:func:`world_rng`, :func:`navigation_rng`). ``ideas-hpc study`` nests draws inside worlds
(:data:`NESTED_STREAM`: world ``m`` of that family, its inner draw ``j`` sample ``m K + j`` of
that design stream).

Stores keep ``s`` in their attrs and, per sample, the first :data:`SEED_WORDS`
words of the sample's sequence state (:func:`seeds_for`), which identify it.

The designers' searches are one-piece runs, not samples, and keep the streams
they have always drawn (so designs stay bit-identical): pygad seeds its own
generator from :func:`search_seed` (``seed mod 2**32``) and each designer's own
draws come from :func:`search_rng` with its purpose word (:data:`GA_SEEDING`,
:data:`PARETO_SEARCH`), ``default_rng([seed mod 2**32, purpose])``. Figures that
jitter points for legibility draw from :func:`plot_rng`, a fixed stream, so the
same store always gives the same picture.
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.base.errors import InputError

#: Words of a sample's SeedSequence state kept in stores (``sample_seed``).
SEED_WORDS = 4

#: Purpose word of the nadir GA's set-cover seeding of its first population.
GA_SEEDING = 13
#: Purpose word of the NSGA-II (design-pareto) search's own draws.
PARETO_SEARCH = 14
#: :func:`search_rng` purpose of the certificate's look plan (issue 41): its bootstrap of
#: the held-out scenarios' values (:mod:`ideas_hpc.design.look_plan`).
LOOK_PLAN = 15
#: Seed of the figures' jitter stream.
PLOT_SEED = 0


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


#: First spawn-key word of the scenario bank's streams (issue 20).
SCENARIO_STREAM = 0x5CE7A210
#: First spawn-key word of a reliability design's validation samples (issue 20).
VALIDATION_STREAM = 0x7A11DA7E
#: Stream of the held-out scenarios that score the swarms the bank chose (issue 41,
#: :mod:`ideas_hpc.design.holdout`): draws of the same dispersions as the bank's and the
#: validation's, disjoint from both (no selection and no certificate uses them).
HOLDOUT_STREAM = 0x401D0B7E
#: Stream of ``ideas-hpc study``'s nested draws (issue 42, the per-target reliability;
#: :mod:`ideas_hpc.campaign.study_nested`): outer world ``m`` is world ``m`` of family
#: ``NESTED_STREAM`` (:func:`world_rng`), and its inner draw ``j`` of navigation errors,
#: dispersions and failures is sample ``m K + j`` of this design stream (``K`` inner draws
#: per world). Disjoint from the bank's, the validation's and the held-out scenarios'.
NESTED_STREAM = 0x4E57ED0D
#: Purposes within one scenario / validation sample (third spawn-key word).
STREAM_BODY, STREAM_SPACECRAFT, STREAM_ATTITUDE = 0, 1, 2
#: Purpose of a validation sample's failures (issue 20: the drawn-failure outcomes;
#: issue 41: then the failure model's own draws, :mod:`ideas_hpc.failures.sampling`).
STREAM_FAILURES = 3
#: Last spawn-key word of the failure model's own draws beside a Monte Carlo sample's
#: dispersion stream (:func:`side_rng`).
FAILURE_SIDE = 0xFA11


def stream_seed_sequence(campaign_seed: int, stream: int, k: int,
                         purpose: int) -> np.random.SeedSequence:
    """``SeedSequence(campaign_seed, spawn_key=(stream, k, purpose))``: draw ``k`` of a design stream.

    ``stream`` is :data:`SCENARIO_STREAM`, :data:`VALIDATION_STREAM`,
    :data:`HOLDOUT_STREAM` or :data:`NESTED_STREAM`; three key words keep these apart from
    every Monte Carlo sample (module docstring).
    """
    if int(stream) not in (SCENARIO_STREAM, VALIDATION_STREAM, HOLDOUT_STREAM, NESTED_STREAM):
        raise InputError(f"unknown design stream {stream!r}", field="stream")
    return np.random.SeedSequence(int(campaign_seed),
                                  spawn_key=(int(stream), int(k), int(purpose)))


def stream_rng(campaign_seed: int, stream: int, k: int, purpose: int) -> np.random.Generator:
    """Generator of :func:`stream_seed_sequence`."""
    return np.random.default_rng(stream_seed_sequence(campaign_seed, stream, k, purpose))


def side_rng(rng: np.random.Generator) -> np.random.Generator:
    """The failure model's own draws beside the stream of ``rng`` (issue 41).

    ``SeedSequence(entropy, spawn_key=key + (FAILURE_SIDE,))`` of the sequence ``rng``
    was made from: it consumes no number of ``rng``, so the Monte Carlo kind's
    dispersions after the failures (drawn from one shared stream, in order) keep their
    numbers when a common-cause event, a prior or a loss time is drawn. Sample ``k``'s
    dispersion stream ``(k, 1)`` gives ``(k, 1, FAILURE_SIDE)``.
    """
    ss = rng.bit_generator.seed_seq
    return np.random.default_rng(np.random.SeedSequence(
        ss.entropy, spawn_key=tuple(ss.spawn_key) + (FAILURE_SIDE,)))


def search_seed(seed: int) -> int:
    """The seed handed to pygad (``random_seed``): ``seed mod 2**32``, a valid numpy seed."""
    return int(seed) % (2**32)


def search_rng(seed: int, purpose: int) -> np.random.Generator:
    """A designer's own stream: ``default_rng([seed mod 2**32, purpose])``.

    ``purpose`` is one of the module's purpose words (:data:`GA_SEEDING`,
    :data:`PARETO_SEARCH`, :data:`LOOK_PLAN`); distinct words give independent streams for
    one seed.
    """
    return np.random.default_rng([search_seed(seed), int(purpose)])


def plot_rng() -> np.random.Generator:
    """The figures' jitter stream, ``default_rng(PLOT_SEED)``: fixed, so figures repeat."""
    return np.random.default_rng(PLOT_SEED)


# ---- target worlds (issue 42) ---------------------------------------------------------------

#: First spawn-key word of the target prior's world draws (issue 42).
WORLD_STREAM = 0x3011D5ED
#: First spawn-key word of the navigation draws of a world (issue 42).
NAVIGATION_STREAM = 0x7A16A7E5
#: Purposes within one world draw (fourth spawn-key word): shape, size, pole, rotation.
WORLD_SHAPE, WORLD_SIZE, WORLD_POLE, WORLD_ROTATION = 0, 1, 2, 3


def world_rng(campaign_seed: int, k: int, purpose: int, family: int = 0) -> np.random.Generator:
    """Generator of world ``k``'s ``purpose`` part: ``SeedSequence(seed, spawn_key=(WORLD_STREAM,
    family, k, purpose))``.

    A world of the target prior (``ideas_hpc.body.target_prior``) draws its shape,
    size, pole and rotation from four independent children (:data:`WORLD_SHAPE`,
    :data:`WORLD_SIZE`, :data:`WORLD_POLE`, :data:`WORLD_ROTATION`), so that changing
    the pole's settings leaves every shape bit-identical. Four key words keep them apart
    from every Monte Carlo sample (one or two words) and every design stream (three).
    ``family`` separates sets of worlds drawn from one campaign seed: 0 for a plain
    draw, :data:`SCENARIO_STREAM` for the scenario bank's worlds and
    :data:`VALIDATION_STREAM` for fresh validation worlds, which then share none.
    """
    if int(purpose) not in (WORLD_SHAPE, WORLD_SIZE, WORLD_POLE, WORLD_ROTATION):
        raise InputError(f"unknown world purpose {purpose!r}", field="purpose")
    return np.random.default_rng(np.random.SeedSequence(
        int(campaign_seed), spawn_key=(WORLD_STREAM, int(family), int(k), int(purpose))))


def navigation_rng(campaign_seed: int, k: int, m: int = 0, family: int = 0) -> np.random.Generator:
    """Generator of navigation draw ``m`` of world ``k``: ``SeedSequence(seed,
    spawn_key=(NAVIGATION_STREAM, family, k, m))``.

    Navigation errors (``ideas_hpc.flyby.navigation``) are nested inside a world for
    the per-target reliability (targets outer ``k``, navigation inner ``m``); a
    design with one navigation draw per world takes ``m = 0``. ``family`` as in
    :func:`world_rng`.
    """
    return np.random.default_rng(np.random.SeedSequence(
        int(campaign_seed), spawn_key=(NAVIGATION_STREAM, int(family), int(k), int(m))))

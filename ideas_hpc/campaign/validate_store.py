"""``ideas-hpc validate``: an independent check of a success-probability design's swarm.

The certificate of a design (docs/certificate.md) already flies fresh samples,
but on the campaign's own seed. This command flies the store's reported swarm
(``swarm_angle``) through ``--samples`` draws of the same ``[monte_carlo]``
dispersions from *another* seed (``--seed``, default the campaign seed + 1), so
that no number of the design run, bank or validation, is reused. Each sample
gives

* the exact failure-weighted success probability of the swarm (failures
  enumerated, as in the design): their mean ``P-hat`` and its one-sided betting
  lower bound (:func:`~ideas_hpc.design.reliability_stats.lower_confidence_bound`);
* one Bernoulli outcome, the same sample with its failures drawn
  (``(VALIDATION_STREAM, m, STREAM_FAILURES)`` of the new seed, as the design's
  validation draws them, :mod:`ideas_hpc.failures.sampling`): the success count and its
  two-sided Wilson score interval (:func:`wilson_interval`), the figure a reader
  can check by hand.

The body must be the one the design saw: a store made on the built-in ellipsoid
(``IDEAS_HPC_DATA`` unset) is validated with it unset too; a mismatch of the
mesh is refused. With ``--truth-shape``, ``--truth-pole``, ``--truth-period-h`` or
``--truth-phase-deg`` every sample flies that one given target instead
(:mod:`ideas_hpc.campaign.validate_truth`; its own mesh and weights).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: z of the two-sided 95 % Wilson interval.
Z95 = 1.959963984540054


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (two-sided, ``z`` standard errors).

    ``(p + z^2 / 2n -+ z sqrt(p (1 - p) / n + z^2 / 4n^2)) / (1 + z^2 / n)`` with
    ``p = successes / n`` (Wilson 1927).
    """
    from ideas_hpc.base.errors import InputError

    if n < 1 or not 0 <= successes <= n:
        raise InputError(f"needs 0 <= successes <= n and n >= 1, got {successes} of {n}",
                         field="samples")
    p = successes / n
    den = 1.0 + z * z / n
    mid = p + z * z / (2 * n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    # the ends are exactly 0 at no success and 1 at all (the rounding would miss them)
    lo = 0.0 if successes == 0 else max(0.0, (mid - half) / den)
    hi = 1.0 if successes == n else min(1.0, (mid + half) / den)
    return lo, hi


class _Outcome:
    """What a validation and a pool of them share (``per_sample``, ``success``, ``lower``,
    ``confidence``, ``p`` fields): the counts, P-hat and the verdict's words."""

    @property
    def successes(self) -> int:
        return int(self.success.sum())

    @property
    def samples(self) -> int:
        return int(self.per_sample.size)

    @property
    def p_hat(self) -> float:
        return float(self.per_sample.mean())

    def verdict(self) -> str:
        """The bound against p, and the drawn successes with their Wilson interval."""
        lo, hi = wilson_interval(self.successes, self.samples)
        return (f"{100 * self.confidence:g} % lower bound {self.lower:.4f} "
                f"{'>=' if self.lower >= self.p else '<'} p = {self.p:g}; with failures "
                f"drawn {self.successes} of {self.samples} succeed "
                f"({self.successes / self.samples:.4f}, Wilson 95 % [{lo:.4f}, {hi:.4f}])")


@dataclass(frozen=True)
class StoreValidation(_Outcome):
    """Outcome of :func:`validate_store`."""

    n: int
    seed: int
    first: int
    per_sample: np.ndarray      # (M,) exact failure-weighted P per sample
    success: np.ndarray         # (M,) bool: the sample maps the threshold, failures drawn
    lower: float                # one-sided betting lower bound on P at ``confidence``
    confidence: float
    p: float
    wall_s: float
    truth: str | None = None    # the given truth, in words (None: the design's worlds)

    def line(self) -> str:
        last = self.first + self.samples - 1
        return (f"independent validation: N = {self.n} swarm, seed {self.seed}, samples "
                f"{self.first}..{last}: P-hat = {self.p_hat:.4f} (failures exact), "
                f"{self.verdict()} in {self.wall_s:.0f} s"
                + (f"; {self.truth}" if self.truth else ""))


def store_campaign(store) -> tuple:
    """``(campaign, attrs)`` of a success-probability design store: its resolved config
    validated again (at the closest-approach distance the design chose, when it chose one
    from ``design.ca_distances_km``), and its root attrs (an input error when it holds no
    such design)."""
    from ideas_hpc.base.errors import InputError
    from ideas_hpc.campaign.schema.campaign_tables import validate_campaign
    from ideas_hpc.campaign.schema.toml_file import CampaignSource
    from ideas_hpc.engine.store_meta import store_attrs

    attrs = store_attrs(Path(store))
    if "reliability_threshold" not in attrs:
        raise InputError(f"{store} holds no success-probability design (no "
                         "reliability_threshold)", field="store")
    cfg = dict(attrs["config"])
    cfg.pop("models", None)
    src = Path(attrs["campaign_file"]) if attrs.get("campaign_file") else None
    c = validate_campaign(CampaignSource(data=cfg, path=src, resolved=True))
    if "chosen_ca_distance_m" in attrs:     # design.ca_distances_km: the swarm flew there
        from ideas_hpc.campaign.study_distance import distance_campaign
        c = distance_campaign(c, float(attrs["chosen_ca_distance_m"]))
    return c, attrs


def validate_store(store, *, samples: int = 1024, seed: int | None = None, first: int = 0,
                   progress: bool = True, same_seed: bool = False,
                   truth=None) -> StoreValidation:
    """Fly a design store's swarm through fresh samples (module docstring).

    ``same_seed`` lets ``seed`` be the design's own (then sample k is the design's
    validation sample k: a check of this command, not an independent validation).
    ``truth``: a :class:`~ideas_hpc.campaign.validate_truth.TruthOptions` (or a
    :class:`~ideas_hpc.body.target_prior.TargetWorld`) every sample flies.
    """
    import xarray as xr

    from ideas_hpc.campaign.validation_flights import (Validation, fly_validation_world,
                                                       sample_weights)
    from ideas_hpc.campaign.setup import requirement_from_campaign, setup_from_campaign
    from ideas_hpc.design.reliability_stats import lower_confidence_bound
    from ideas_hpc.base.errors import InputError
    from ideas_hpc.mapping.requirement import meets
    from ideas_hpc.montecarlo.failure_dispersion import failure_model

    if samples < 1:
        raise InputError(f"must be >= 1, got {samples}", field="--samples")
    c, attrs = store_campaign(store)
    seed = int(attrs["campaign_seed"]) + 1 if seed is None else int(seed)
    if seed == int(attrs["campaign_seed"]) and not same_seed:
        raise InputError(f"{seed} is the design's own seed: give another", field="--seed")
    ds = xr.open_zarr(store)
    theta = np.asarray(ds["swarm_angle"].values, dtype=np.float64)
    # the design's weights: its reference area (issue 42) or the whole surface
    w = np.asarray(ds["reference_area" if "reference_area" in ds else "vertex_area"].values,
                   dtype=np.float64)
    w = w / w.sum()
    setup = setup_from_campaign(c)
    setup, truth_words = _given_truth(setup, truth, c.config.body.resolution)
    mc = c.config.monte_carlo
    t0 = time.perf_counter()
    model = failure_model(mc)
    rows, seen, areas = fly_validation_world(setup, theta, mc, model,
                                             requirement_from_campaign(c), seed=seed,
                                             n_samples=int(samples), progress=progress,
                                             first=int(first))
    if truth_words is None and rows.shape[2] != w.size:
        raise InputError(f"the body flown now has {rows.shape[2]} vertices, the store's "
                         f"{w.size} ({attrs.get('body', '?')}): set IDEAS_HPC_DATA as the "
                         "design run had it", field="store")
    need = float(attrs["reliability_threshold"])
    # the design's own validation (failures.sampling): exact P and one drawn outcome each
    # drawn worlds (issue 42): each flight's own weights; a store whose bank had weights by
    # scenario refuses flights that bring none (validation_flights.sample_weights)
    bank_w = (np.asarray(ds["scenario_vertex_weight"].values)
              if "scenario_vertex_weight" in ds else w)
    v = Validation(rows, sample_weights(areas, bank_w, rows.shape[0]), need, model, seed,
                   first=int(first), seen=seen)
    per = v.per_sample
    # the same tolerance as the exact enumeration (the requirement's one comparison)
    wins = meets(v.coverage, need)
    conf = float(attrs["confidence"])
    return StoreValidation(n=theta.size, seed=seed, first=int(first), per_sample=per,
                           success=wins,
                           lower=lower_confidence_bound(per, conf), confidence=conf,
                           p=float(attrs["success_probability"]),
                           wall_s=time.perf_counter() - t0, truth=truth_words)


@dataclass(frozen=True)
class Pooled(_Outcome):
    """Several validations of one design as one sample (:func:`pooled`)."""

    per_sample: np.ndarray
    success: np.ndarray
    lower: float
    confidence: float
    p: float
    truths: int

    def line(self) -> str:
        return (f"pooled over {self.truths} given truths, {self.samples} samples: P-hat = "
                f"{self.p_hat:.4f}, {self.verdict()}")


def pooled(validations) -> Pooled:
    """Pool :class:`StoreValidation` results of one design, e.g. several given truths
    (:mod:`ideas_hpc.campaign.validate_truth`): P-hat = sum of per-sample P / total
    samples, its bound by the validation's own bound function at the store's confidence,
    the drawn successes summed with their Wilson interval."""
    from ideas_hpc.base.errors import InputError
    from ideas_hpc.design.reliability_stats import lower_confidence_bound

    vs = list(validations)
    if not vs:
        raise InputError("needs at least one validation", field="validations")
    if len({(v.confidence, v.p) for v in vs}) != 1:
        raise InputError("the validations are of different designs (confidence or p differ)",
                         field="validations")
    per = np.concatenate([np.asarray(v.per_sample, dtype=np.float64) for v in vs])
    return Pooled(per_sample=per, success=np.concatenate([np.asarray(v.success) for v in vs]),
                  lower=lower_confidence_bound(per, vs[0].confidence),
                  confidence=vs[0].confidence, p=vs[0].p, truths=len(vs))


def _given_truth(setup, truth, resolution: int):
    """``(setup, words)``: ``setup`` flying the given truth and its description, or
    ``(setup, None)`` when none is given."""
    from ideas_hpc.body.target_prior import TargetWorld
    from ideas_hpc.campaign.validate_truth import (TruthOptions, describe, options_world,
                                                   truth_setup)

    if truth is None or (isinstance(truth, TruthOptions) and not truth.given):
        return setup, None
    if isinstance(truth, TargetWorld):
        world, words = truth, describe(truth, TruthOptions(shape="given world"))
    else:
        world = options_world(setup, truth, resolution)
        words = describe(world, truth)
    return truth_setup(setup, world), words


def _cmd_validate(args) -> int:
    from ideas_hpc.campaign.validate_truth import truth_options

    truth = truth_options(args.truth_shape, args.truth_pole, args.truth_period_h,
                          args.truth_phase_deg)
    v = validate_store(args.store, samples=args.samples, seed=args.seed, first=args.first,
                       progress=not args.no_progress, truth=truth)
    print(v.line())
    if args.out:
        np.savez(args.out, per_sample=v.per_sample, success=v.success, seed=v.seed,
                 first=v.first, n=v.n)
        print(f"per-sample values: {args.out}")
    return 0


def add_validate_command(sub) -> None:
    p = sub.add_parser("validate", help="fly a design store's swarm through fresh samples "
                                        "from another seed",
                       description="Independent validation of a success-probability design: "
                                   "the store's swarm flown through fresh draws of the same "
                                   "dispersions from a seed the design never used; prints "
                                   "P-hat with its lower bound and the success count with "
                                   "its Wilson interval (docs/certificate.md).")
    p.add_argument("store", help="store of a design-nadir run with design.success_probability")
    p.add_argument("--samples", type=int, default=1024, help="fresh samples (default 1024)")
    p.add_argument("--seed", type=int, default=None,
                   help="seed of the fresh samples (default: the campaign seed + 1)")
    p.add_argument("--first", type=int, default=0, help="first sample index (default 0)")
    p.add_argument("--out", default=None,
                   help="also write the per-sample values (.npz: per_sample, success)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    t = p.add_argument_group("a given truth (every sample flies this one target; navigation "
                             "errors, dispersions and failures still drawn; an option left "
                             "out takes the design's nominal value)")
    t.add_argument("--truth-shape", default=None, metavar="FILE|NAME",
                   help="shape file (km; its body frame, origin at the centre of mass), "
                        "built-in body name, or ellipsoid:A,B,C (semi-axes, km)")
    t.add_argument("--truth-pole", default=None, metavar="RA,DEC",
                   help="spin pole, deg, J2000 equatorial")
    t.add_argument("--truth-period-h", type=float, default=None, help="spin period, h")
    t.add_argument("--truth-phase-deg", type=float, default=None,
                   help="rotation angle W at closest approach, deg")
    p.set_defaults(handler=_cmd_validate)

"""The store variables (SPEC section 9): names, dims, dtypes, units, descriptions.

The one place a result variable is declared. Flyby and design stores use the
dims as written; Monte Carlo stores put ``sample`` first on the per-sample
ones (:data:`PER_SAMPLE`). The Monte Carlo dispersions declare their own
variables with the same :class:`StoreVar` (:mod:`ideas_hpc.montecarlo.dispersions`),
next to the draw that fills them.

Dims: ``sample``, ``spacecraft``, ``time``, ``iteration``, ``vertex``,
``axis`` (x, y, z), ``wheel``, ``generation``, ``individual``, ``gene``, plus
``face``/``corner`` for the stored mesh and ``snapshot``/``row``/``col`` for
camera DCMs at a few instants; design stores add ``n_spacecraft``,
``verify_sample``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class StoreVar:
    """One store variable: dims (without a leading ``sample``), dtype, units, description."""

    name: str
    dims: tuple[str, ...]
    dtype: type = np.float64
    units: str | None = "1"
    long_name: str | None = None

    def attrs(self) -> dict:
        return {k: v for k, v in (("units", self.units), ("long_name", self.long_name)) if v}


V, SC, T = ("vertex",), ("spacecraft",), ("spacecraft", "time")
_VARS = (
    StoreVar("swarm_angle", SC, units="rad", long_name="swarm angle theta_i"),
    StoreVar("sweep_period", SC, units="s", long_name="FoV sweep period P_i"),
    StoreVar("position", T + ("axis",), units="m", long_name="spacecraft position, frame T"),
    StoreVar("velocity", T + ("axis",), units="m/s", long_name="spacecraft velocity, frame T"),
    StoreVar("targeting_miss", ("spacecraft", "iteration"), units="m",
             long_name="|dr_k| per Newton iteration (NaN: not run)"),
    StoreVar("targeting_v0", SC + ("axis",), units="m/s",
             long_name="targeted initial velocity, frame T"),
    StoreVar("arrival_error", SC, units="m", long_name="final position minus nominal"),
    StoreVar("sigma_error", T + ("axis",), long_name="MRP attitude error sigma_B/R"),
    StoreVar("omega_error", T + ("axis",), units="rad/s",
             long_name="rate error omega_B/R, frame B"),
    StoreVar("wheel_speed", T + ("wheel",), units="rad/s", long_name="reaction wheel speed Omega"),
    StoreVar("wheel_torque", T + ("wheel",), units="N m", long_name="reaction wheel torque u_s"),
    StoreVar("images_discarded_smear", SC, np.int32, units="1",
             long_name="images not used: the scene's image at the footprint centre moves "
             "more than smear_pixels during the exposure"),
    StoreVar("images_discarded_settle", SC, np.int32, units="1",
             long_name="images not used: attitude error above settle_deg"),
    StoreVar("camera_dcm_BT", SC + ("snapshot", "row", "col"),
             long_name="camera DCM [BT] (B <- T) at snapshots"),
    StoreVar("observed", V, bool, long_name="vertex observed (paper eq. 26)"),
    StoreVar("first_seen", V, units="s", long_name="first time the vertex was imaged (NaN: never)"),
    StoreVar("times_seen", V, np.int32, long_name="number of images that saw the vertex"),
    StoreVar("coverage", (), long_name="area-weighted fraction observed (mapped when a "
             "[coverage] requirement is set)"),
    StoreVar("coverage_seen", (), long_name="area-weighted fraction observed"),
    StoreVar("coverage_count", (), long_name="vertex-count fraction observed"),
    StoreVar("lit", V, bool, long_name="sunlit and unshadowed at some observation"),
    StoreVar("best_resolution", V, units="m", long_name="best effective ground sample "
             "rho*range/cos(emission) (NaN: never observed)"),
    StoreVar("emission_at_best", V, units="rad",
             long_name="emission angle at the best-resolution observation"),
    StoreVar("incidence_at_best", V, units="rad",
             long_name="incidence angle at the best-resolution observation"),
    StoreVar("phase_at_best", V, units="rad",
             long_name="phase angle at the best-resolution observation"),
    StoreVar("n_spacecraft_seen", V, np.int32, long_name="spacecraft that observed the vertex"),
    StoreVar("stereo", V, bool, long_name="two usable observations with a convergence angle "
             "in [stereo_min, stereo_max]"),
    StoreVar("mapped", V, bool, long_name="vertex meets the [coverage] requirement"),
    StoreVar("vertex_position", ("vertex", "axis"), units="m",
             long_name="shape model vertex, frame T"),
    StoreVar("vertex_area", V, units="m^2", long_name="vertex area (1/3 of adjacent faces)"),
    StoreVar("face_vertices", ("face", "corner"), np.int32,
             long_name="vertex indices of each face"),
    StoreVar("pointing_rate", SC, units="rad/s",
             long_name="peak angular rate the pointing profile asks for (inertial)"),
    StoreVar("pointing_torque", SC, units="N m",
             long_name="peak torque I w' + w x I w the pointing profile asks of the wheels"),
    StoreVar("pointing_momentum", SC, units="N m s",
             long_name="peak body momentum |I w| the wheels must absorb"),
    StoreVar("pointing_feasible", SC, bool,
             long_name="pointing torque and momentum within the wheel limits"),
    StoreVar("best_fitness", ("generation",), long_name="best fitness"),
    StoreVar("mean_fitness", ("generation",), long_name="population mean fitness"),
    StoreVar("population", ("individual", "gene"), long_name="final population genomes"),
    StoreVar("fitness", ("individual",), long_name="fitness of the final population"),
    StoreVar("population_coverage", ("individual",),
             long_name="area coverage of the final population"),
    StoreVar("best_genome", ("gene",), long_name="best genome"),
    StoreVar("snapshot_time", ("snapshot",), units="s", long_name="time of each DCM snapshot"),
    StoreVar("max_wheel_torque", SC, units="N m", long_name="largest reaction wheel torque"),
    StoreVar("max_wheel_momentum", SC, units="N m s",
             long_name="largest reaction wheel angular momentum"),
    # designs (issue 13): dimensionless counts and fractions are units "1" (CF)
    StoreVar("design_method", (), str, long_name="design method (exact, ga)"),
    StoreVar("best_swarm_size", (), np.int64, long_name="spacecraft in the design"),
    StoreVar("best_coverage", (), long_name="coverage of the design, area fraction (mapped "
             "when a [coverage] requirement is set)"),
    StoreVar("best_coverage_of_reference", (), long_name="coverage of the design, fraction "
             "of the reference area (design.coverage_reference)"),
    StoreVar("reference_area", V, units="m^2", long_name="vertex weight of the coverage "
             "reference: its area in the reference, 0 outside (design.coverage_reference)"),
    StoreVar("design_coverage", (), long_name="coverage of the design on the designer's "
             "candidate masks, area fraction"),
    StoreVar("proven_bound", (), long_name="proven lower bound on the number of spacecraft"),
    StoreVar("optimality_gap", (), long_name="(N - proven lower bound) / N"),
    StoreVar("solver_status", (), str, long_name="solver status (optimal, time_limit, ...)"),
    StoreVar("solve_time", (), units="s", long_name="wall time of the design solve"),
    StoreVar("failure_cases", (), np.int64, long_name="failure cases evaluated"),
    StoreVar("worst_failure", ("failed",), np.int32,
             long_name="spacecraft whose failure gives the worst case"),
    StoreVar("coverage_vs_n", ("n_spacecraft",),
             long_name="best coverage of N spacecraft, area fraction"),
    StoreVar("coverage_vs_n_gap", ("n_spacecraft",),
             long_name="proven upper bound minus the coverage found for N spacecraft"),
    StoreVar("coverage_vs_n_status", ("n_spacecraft",), str,
             long_name="solver status of each point of the coverage-vs-N curve"),
    StoreVar("coverage_vs_n_swarm", ("n_spacecraft", "slot"), units="rad",
             long_name="swarm angles of the best N-spacecraft swarm (NaN beyond N)"),
    StoreVar("verify_coverage", ("verify_sample",),
             long_name="coverage of each dispersed verification sample"),
    StoreVar("verify_n_failed", ("verify_sample",), np.int32,
             long_name="failed spacecraft in each verification sample"),
    # written by the engine into every store
    StoreVar("chunk_done", ("chunk",), bool,
             long_name="chunk finished (True once all its samples are written, written last)"),
    StoreVar("chunk_start", ("chunk",), np.int64, long_name="first sample of the chunk"),
    StoreVar("chunk_stop", ("chunk",), np.int64, long_name="end of the chunk (exclusive)"),
    StoreVar("sample_seed", ("sample", "seed_word"), np.uint32,
             long_name="first 4 words of SeedSequence(campaign_seed, spawn_key=(sample,))"),
)
VARS: dict[str, StoreVar] = {v.name: v for v in _VARS}

#: Per-vertex results of the quality pass (issue 14), stored when it runs.
QUALITY = ("lit", "best_resolution", "emission_at_best", "incidence_at_best", "phase_at_best",
           "n_spacecraft_seen", "stereo", "mapped")
#: Results of one flight: a Monte Carlo store gives each a leading ``sample`` dim.
PER_SAMPLE = ("coverage", "coverage_count", "coverage_seen", "observed", "first_seen",
              "times_seen", "arrival_error")
#: Closed-loop attitude series (simulated attitude only).
ATTITUDE_SERIES = ("sigma_error", "omega_error", "wheel_speed", "wheel_torque")
#: Images discarded per spacecraft (simulated attitude with the usable-image test on).
DISCARDS = ("images_discarded_smear", "images_discarded_settle")


#: Index coordinates: dim -> (units, long_name). Every dim of a store gets one
#: (:func:`describe`); those without natural values count from 0.
DIMS: dict[str, tuple[str, str]] = {
    "sample": ("1", "Monte Carlo sample"),
    "spacecraft": ("1", "spacecraft"),
    "time": ("s", "time since the flyby start t0"),
    "iteration": ("1", "targeting Newton iteration"),
    "vertex": ("1", "shape model vertex"),
    "face": ("1", "shape model face"),
    "corner": ("1", "corner of a face"),
    "axis": ("1", "Cartesian axis"),
    "wheel": ("1", "reaction wheel"),
    "snapshot": ("1", "camera DCM snapshot"),
    "row": ("1", "DCM row"),
    "col": ("1", "DCM column"),
    "generation": ("1", "GA generation"),
    "individual": ("1", "member of the final GA population"),
    "gene": ("1", "GA gene"),
    "n_spacecraft": ("1", "number of spacecraft N"),
    "slot": ("1", "spacecraft slot of a swarm (NaN-padded)"),
    "pareto": ("1", "point of the Pareto front"),
    "verify_sample": ("1", "Monte Carlo verification sample"),
    "failed": ("1", "failed spacecraft of the worst case"),
    "chunk": ("1", "campaign chunk"),
    "seed_word": ("1", "word of the sample's seed state"),
}


def describe(ds):
    """Make ``ds`` self-describing (CF style): a coordinate on every dim, ``units``
    (``"1"`` when dimensionless) and ``long_name`` on every variable declared
    here. Returns a new dataset; undeclared variables keep their attrs."""
    missing = {d: np.arange(n) for d, n in ds.sizes.items() if d not in ds.coords}
    ds = ds.assign_coords(missing) if missing else ds.copy(deep=False)
    for d in ds.dims:
        units, long_name = DIMS.get(d, ("1", d))
        ds[d].attrs.setdefault("units", units)
        ds[d].attrs.setdefault("long_name", long_name)
    return with_attrs(ds)


def with_attrs(ds):
    """Put every declared variable's units and description on ``ds`` (in place; returned)."""
    for name in ds.variables:
        v = VARS.get(name)
        if v is not None:
            ds[name].attrs.update(v.attrs())
    return ds

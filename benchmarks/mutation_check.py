"""Mutation check: does the test suite catch small, realistic bugs? (issue 34)

Each mutation names a file, a text that occurs exactly once in it, its replacement,
and the test node ids that must catch it. The script applies one mutation, runs
those tests (``pytest -x -q``), records caught (the tests failed) or missed (they
passed), and restores the file byte for byte with its original mtime (so Numba's
on-disk cache of the untouched kernel stays valid). The file is restored on every
exit path, Ctrl-C included. A mutation of compiled code (``ideas_hpc/core/``) runs
with an empty ``NUMBA_CACHE_DIR``: Numba's cache checks only a kernel's own file, so
a kernel in another file that inlines the mutated one would otherwise run its stale
cached machine code and the mutation would never be tested.

Run from the repository root (a copy of the worktree is wise: the tree is modified
while it runs)::

    PYTHONPATH=$PWD IDEAS_HPC_DATA=../shared/data python benchmarks/mutation_check.py
    python benchmarks/mutation_check.py --only targeting_stm_transposed --list

Exit status 1 when a mutation is missed or does not apply.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


@dataclass(frozen=True)
class Mutation:
    name: str
    area: str           # designers, statistics, store, kernels, schema
    path: str           # relative to the repository root
    old: str            # occurs exactly once in the file
    new: str
    tests: tuple[str, ...]


M = Mutation
MUTATIONS: tuple[Mutation, ...] = (
    # ---- kernels
    M("targeting_stm_transposed", "kernels", "ideas_hpc/core/dynamics/targeting.py",
      "prv[i, j] = y[6 + 6 * i + 3 + j]", "prv[j, i] = y[6 + 6 * i + 3 + j]",
      ("tests/test_targeting.py::test_newton_converges_quadratically",)),
    M("sliding_mode_sd2_cross_sign", "kernels", "ideas_hpc/core/attitude/control.py",
      "sd2 = 0.25 * (q * e2 + 2.0 * (d3 * e1 - d1 * e3)",
      "sd2 = 0.25 * (q * e2 + 2.0 * (d3 * e1 + d1 * e3)",
      ("tests/test_sliding_surface.py",)),
    M("mrp_shadow_threshold", "kernels", "ideas_hpc/core/attitude/mrp.py",
      "    if s2 > 1.0:\n        return -sigma / s2", "    if s2 > 1.5:\n        return -sigma / s2",
      ("tests/test_mrp.py",)),
    M("gravity_c22_factor", "kernels", "ideas_hpc/core/dynamics/gravity.py",
      "q0 = -0.5 * c20 + 3.0 * c22", "q0 = -0.5 * c20 + 1.5 * c22",
      ("tests/test_gravity.py::test_degree2_matches_closed_form_spec_u2",)),
    M("elevation_mask_sign", "kernels", "ideas_hpc/core/mapping/visibility.py",
      "if not los_n >= rng * sin_min_elev:", "if not los_n >= -rng * sin_min_elev:",
      ("tests/test_coverage.py::test_brute_force_strict_elevation_range",)),
    M("union_skips_first_member", "kernels", "ideas_hpc/core/design/union.py",
      "            if k < 0:\n                continue", "            if k < 0 or s == 0:\n                continue",
      ("tests/test_campaign_design.py::test_population_coverage_matches_numpy",)),
    M("cuda_image_error_angle", "kernels", "ideas_hpc/core/attitude/batch_cuda.py",
      "img_err[smp, i, n_img_done] = 4.0 * math.atan(",
      "img_err[smp, i, n_img_done] = 2.0 * math.atan(",
      ("tests/test_bank_cuda.py::test_cuda_kernel_and_bank_rows_match_the_cpu_under_the_simulator",)),
    M("cuda_integral_wrong_axis", "kernels", "ideas_hpc/core/attitude/batch_cuda.py",
      "z[1] += err[1] * dt", "z[1] += err[0] * dt",
      ("tests/test_bank_cuda.py::test_cuda_kernel_and_bank_rows_match_the_cpu_under_the_simulator",)),
    M("cuda_world_rows_clear_cone_flipped", "kernels", "ideas_hpc/core/mapping/world_rows_cuda.py",
      "if opts.occlusion and not ln >= math.sqrt(rng2)",
      "if opts.occlusion and ln >= math.sqrt(rng2)",
      ("tests/test_world_rows_cuda.py::test_cuda_rows_are_the_cpu_kernels_and_full_recomputation",)),
    M("cuda_world_rows_bvh_left_twice", "kernels", "ideas_hpc/core/mapping/world_rows_cuda.py",
      "stack[sp + 1] = node_info[node, 1]", "stack[sp + 1] = node_info[node, 0]",
      ("tests/test_world_rows_cuda.py::test_cuda_rows_are_the_cpu_kernels_and_full_recomputation",)),
    M("cuda_world_rows_elevation_sign", "kernels", "ideas_hpc/core/mapping/world_rows_cuda.py",
      "if not (-dx) * nx + (-dy) * ny + (-dz) * nz >= rng * opts.sin_min_elev:",
      "if not dx * nx + dy * ny + dz * nz >= rng * opts.sin_min_elev:",
      ("tests/test_world_rows_cuda.py::test_cuda_rows_are_the_cpu_kernels_and_full_recomputation",)),
    M("cuda_world_rows_not_selected", "kernels", "ideas_hpc/mapping/world_rows.py",
      'if device == "cuda":', 'if device == "gpu":',
      ("tests/test_world_rows_cuda.py::test_run_device_cuda_sends_world_rows_to_the_kernel",)),
    M("device_not_passed_to_flights", "kernels", "ideas_hpc/flyby/camera.py",
      'device=getattr(setup, "device", "cpu")', 'device="cpu"',
      ("tests/test_bank_cuda.py::test_cuda_kernel_and_bank_rows_match_the_cpu_under_the_simulator",)),
    # ---- smear relative to the scene (SPEC 7d corrected, issue 42)
    M("smear_camera_rate_only", "kernels", "ideas_hpc/core/attitude/smear.py",
      "    ox = wx - c02 * spin - vy * inv\n    oy = wy - c12 * spin + vx * inv",
      "    ox = wx\n    oy = wy",
      ("tests/test_smear.py",)),
    M("smear_los_sign", "kernels", "ideas_hpc/core/attitude/smear.py",
      "    ox = wx - c02 * spin - vy * inv\n    oy = wy - c12 * spin + vx * inv",
      "    ox = wx - c02 * spin + vy * inv\n    oy = wy - c12 * spin - vx * inv",
      ("tests/test_smear.py",)),
    M("smear_spin_left_out", "kernels", "ideas_hpc/core/attitude/smear.py",
      "    ox = wx - c02 * spin - vy * inv\n    oy = wy - c12 * spin + vx * inv",
      "    ox = wx - vy * inv\n    oy = wy + vx * inv",
      ("tests/test_smear.py::test_smear_rate_is_the_image_motion_over_the_exposure",)),
    M("smear_far_intersection", "kernels", "ideas_hpc/core/attitude/smear.py",
      "    num = far if ahead else 1.0\n    den = q if ahead else (far if inside else s)",
      "    num = 1.0\n    den = far if ahead | inside else s",
      ("tests/test_smear.py",)),
    M("smear_lanes_chunk_off_by_one", "kernels", "ideas_hpc/core/attitude/camera_lanes.py",
      "q = n_img_done % _CHUNK", "q = (n_img_done + 1) % _CHUNK",
      ("tests/test_scenario_flight.py::test_one_pass_flight_is_the_pipeline_flight",)),
    M("smear_batch_path_without_spin", "kernels", "ideas_hpc/flyby/camera.py",
      "float(setup.body.params.spin_rate), scene_radius_m(setup.body.shape))",
      "0.0, scene_radius_m(setup.body.shape))",
      ("tests/test_scenario_flight.py::test_one_pass_flight_is_the_pipeline_flight",)),
    # ---- perfect tracking faces smear at its reference's rate (issue 42)
    M("ideal_track_rate_dropped", "kernels", "ideas_hpc/flyby/camera.py",
      "            return track_omega_BN_B(setup, r_img, v_img)",
      "            return 0.0 * track_omega_BN_B(setup, r_img, v_img)",
      ("tests/test_smear.py::"
       "test_ideal_attitude_at_a_fast_pass_keeps_tracked_images_and_loses_fixed_ones",)),
    M("ideal_track_rate_sign", "kernels", "ideas_hpc/flyby/encounter.py",
      "    return track_rates(r_N, v_N, np.ascontiguousarray(setup.encounter.dcm_NS[:, 2]))",
      "    return -track_rates(r_N, v_N, np.ascontiguousarray(setup.encounter.dcm_NS[:, 2]))",
      ("tests/test_smear.py::"
       "test_ideal_attitude_at_a_fast_pass_keeps_tracked_images_and_loses_fixed_ones",)),
    M("ideal_aim_centroid_not_turned", "kernels", "ideas_hpc/flyby/nav_flight.py",
      "    if centroid_dcm is None or not lock.any():\n        return w\n",
      "    if True:\n        return w\n",
      ("tests/test_smear.py::"
       "test_ideal_tracking_rate_with_navigation_errors_is_the_turn_of_its_cameras",)),
    M("ideal_ring_rate_without_spin", "kernels", "ideas_hpc/flyby/camera.py",
      "w, ts = setup.geometry.maneuver_frame(setup, setup.body.params.spin_rate)\n    return",
      "w, ts = setup.geometry.maneuver_frame(setup, 0.0)\n    return",
      ("tests/test_smear.py::test_the_papers_nadir_pass_keeps_every_image_in_ideal_attitude",)),
    M("ideal_images_never_tested", "kernels", "ideas_hpc/flyby/views.py",
      "closed or flown.geometry.ideal_images_tested)", "closed)",
      ("tests/test_smear.py::"
       "test_ideal_attitude_at_a_fast_pass_keeps_tracked_images_and_loses_fixed_ones",)),
    # ---- the world a flight flies through (issue 40)
    M("world_sun_ignores_its_pole", "kernels", "ideas_hpc/flyby/world.py",
      "return sun_direction_T(self.params, self.epoch_s", "return sun_direction_T(self.body.params, self.epoch_s",
      ("tests/test_world.py::test_the_sun_of_a_world_follows_its_pole",)),
    M("world_statics_keyed_without_spin", "kernels", "ideas_hpc/flyby/world.py",
      "return (self.spin_rate_rad_s, repr(self.encounter), float(self.shape.r_max))",
      "return (repr(self.encounter), float(self.shape.r_max))",
      ("tests/test_world.py::test_a_world_flies_what_a_body_with_its_parameters_flies",)),
    M("rows_ignore_the_worlds_sun", "kernels", "ideas_hpc/montecarlo/scenario_rows.py",
      "if world is not None and (world.mapping_key(self.setup)",
      "if False and (world.mapping_key(self.setup)",
      ("tests/test_recipes.py::test_recipe_world_dispersion_the_pole",)),
    # ---- one world per scenario from the target prior (issue 42)
    M("target_world_frame_transposed", "world", "ideas_hpc/flyby/target_world.py",
      "q = nominal_dcm_TN(setup) @ dcm_TN(base, tw.pole_lon_lat_rad, tw.phase_tca_rad).T",
      "q = dcm_TN(base, tw.pole_lon_lat_rad, tw.phase_tca_rad) @ nominal_dcm_TN(setup).T",
      ("tests/test_target_worlds.py::test_world_is_placed_by_its_pole_and_phase",)),
    M("target_world_streams_shared", "world", "ideas_hpc/flyby/target_world.py",
      "prior.draw(int(seed), int(k), family=int(family))", "prior.draw(int(seed), int(k))",
      ("tests/test_target_worlds.py::test_streams_give_disjoint_worlds",)),
    M("bank_flies_the_nominal_world", "world", "ideas_hpc/montecarlo/scenarios.py",
      "        if setup.target is None:\n            row = engine.scenario_rows(pert, reuse=True)",
      "        if True:\n            row = engine.scenario_rows(pert, reuse=True)",
      ("tests/test_target_worlds.py::test_drawn_rows_are_full_recomputations",)),
    # ---- the world bank's shortcuts (issue 43)
    M("world_pass_tree_ignores_the_turn", "world", "ideas_hpc/core/mapping/pass_tree.py",
      "    spread = rec[N_EC] * pabs + fp", "    spread = fp",
      ("tests/test_world_bank.py::test_pass_tree_rejects_only_runs_that_no_image_sees",)),
    M("world_clear_cone_skips_straddling_faces", "world",
      "ideas_hpc/core/mapping/world_statics.py",
      "                if max(h0, h1, h2) < below:", "                if min(h0, h1, h2) < below:",
      ("tests/test_world_bank.py::test_clear_cones_hold_no_blocked_sight_line",)),
    M("world_sun_cone_covers_its_axis_only", "world", "ideas_hpc/core/mapping/world_statics.py",
      "                half[nr - 1] = max(half[nr - 1], ang)",
      "                half[nr - 1] = half[nr - 1]",
      ("tests/test_world_bank.py::test_lighting_table_is_the_shadow_ray_test",)),
    M("world_rows_guess_without_light", "world", "ideas_hpc/core/mapping/world_rows.py",
      "    if need_lit and not lit[j, i]:", "    if need_lit and not lit[j, 0]:",
      ("tests/test_world_bank.py::test_world_bank_rows_are_full_recomputations",)),
    # ---- validation at a given truth (issue 42, deliverable 7)
    M("truth_ignored_drawn_world_flown", "world", "ideas_hpc/campaign/validate_truth.py",
      "return dataclasses.replace(setup, target=GivenTruth(world))", "return setup",
      ("tests/test_validate_truth.py::test_a_drawn_world_given_as_truth_flies_as_drawn",)),
    M("truth_pole_ignored", "world", "ideas_hpc/campaign/validate_truth.py",
      "pole_N = pole0 if pole_ra_dec_rad is None else", "pole_N = pole0 if True else",
      ("tests/test_validate_truth.py::test_a_drawn_world_given_as_truth_flies_as_drawn",)),
    M("truth_phase_ignored", "world", "ideas_hpc/campaign/validate_truth.py",
      "phase_tca_rad=phase0 if phase_rad is None else float(phase_rad)",
      "phase_tca_rad=phase0",
      ("tests/test_validate_truth.py::test_a_drawn_world_given_as_truth_flies_as_drawn",)),
    # ---- ideas-hpc study: the answers under a target prior (issue 42, deliverable 6)
    M("study_known_is_the_prior", "study", "ideas_hpc/campaign/study.py",
      "known = dataclasses.replace(st.setup, target=None)", "known = st.setup",
      ("tests/test_study.py::test_no_spread_costs_nothing_and_the_known_case_is_the_nominal",)),
    M("study_monotone_flag_reversed", "study", "ideas_hpc/campaign/study.py",
      "monotone = bool(np.all(np.diff(sp) >= -1e-12))",
      "monotone = bool(np.all(np.diff(sp) <= 1e-12))",
      ("tests/test_study.py::test_late_update_draws_common_random_numbers_and_p_is_monotone",)),
    M("nested_world_of_sample_wraps", "study", "ideas_hpc/campaign/study_nested.py",
      "return int(k) // int(self.per_world)", "return int(k) % int(self.per_world)",
      ("tests/test_study.py::test_each_nested_world_is_its_truth_flown_through_its_inner_draws",)),
    M("nested_worlds_are_the_banks", "study", "ideas_hpc/campaign/study_nested.py",
      "world_family: int = seeds.NESTED_STREAM", "world_family: int = seeds.SCENARIO_STREAM",
      ("tests/test_study.py::test_each_nested_world_is_its_truth_flown_through_its_inner_draws",)),
    M("nested_blocks_transposed", "study", "ideas_hpc/campaign/study_nested.py",
      "block = v.reshape(-1, k)", "block = v.reshape(k, -1).T",
      ("tests/test_study.py::test_conditional_probabilities_by_hand",
       "tests/test_study.py::test_no_spread_every_world_is_the_plain_p")),
    M("study_distance_not_applied", "study", "ideas_hpc/campaign/study_distance.py",
      'data.setdefault("flyby", {})["d_sep_km"] = float(d_m) / KM',
      'data.setdefault("flyby", {})["d_sep_km"] = None',
      ("tests/test_study_distance.py::"
       "test_own_distance_is_the_design_and_others_apply_their_distance",)),
    M("study_distance_gsd_from_range", "study", "ideas_hpc/campaign/study_distance.py",
      'return {"gsd_m": (d - setup.sizing.r_av) * float(ifov)',
      'return {"gsd_m": d * float(ifov)',
      ("tests/test_study_distance.py::"
       "test_gsd_is_the_sizings_at_its_radius_and_the_los_rate_is_v_over_d",)),
    M("design_distance_tie_flipped", "designers", "ideas_hpc/campaign/design_distance.py",
      "(int(n[i]), not bool(proven[i]), -float(probability[i]), i)",
      "(int(n[i]), not bool(proven[i]), float(probability[i]), i)",
      ("tests/test_design_distance.py::test_the_rule",)),
    M("design_distance_most_n", "designers", "ideas_hpc/campaign/design_distance.py",
      "(int(n[i]), not bool(proven[i]), -float(probability[i]), i)",
      "(-int(n[i]), not bool(proven[i]), -float(probability[i]), i)",
      ("tests/test_design_distance.py::test_the_rule",)),
    M("design_distance_not_flown", "designers", "ideas_hpc/campaign/design_distance.py",
      "    out.flown = (row.c, row.setup)", "    out.flown = None",
      ("tests/test_design_distance.py::"
       "test_the_design_over_distances_is_the_brute_force_of_single_distance_designs",)),
    # ---- designers
    M("best_of_clock_after_search", "designers", "ideas_hpc/design/reliability.py",
      "        clock = not self.settled", "        clock = True",
      ("tests/test_stop_signals.py::test_sizes_past_the_search_do_not_depend_on_the_clock",)),
    M("ring_bound_optimistic_single", "designers", "ideas_hpc/core/design/ring_gaps.py",
      "tot[1, s] = M[s, K]", "tot[1, s] = 0.5 * M[s, K]",
      ("tests/test_ring_bound.py::test_bound_is_the_least_gap_miss_and_never_above_the_truth",)),
    M("polish_separation_off_by_one", "designers", "ideas_hpc/design/ring_bound.py",
      "ok = (np.minimum(d, k - d) > m).all(axis=1) & (cov >= need)",
      "ok = (np.minimum(d, k - d) >= m).all(axis=1) & (cov >= need)",
      ("tests/test_ring_bound.py::test_redundancy_polish_never_breaks_the_separation",)),
    M("screen_one_member_never_listed", "designers", "ideas_hpc/core/design/ring_screen.py",
      "        if n == 1:          # no second member", "        if n == 0:          # no second member",
      ("tests/test_screen_sizes.py::test_screen_lists_every_subset_of_every_size",
       "tests/test_screen_sizes.py::test_screen_size_agrees_with_the_exhaustive_search")),
    M("screen_kernel_cut_list_complete", "designers", "ideas_hpc/core/design/ring_screen.py",
      "                return out[:found], cnt[:found], False\n            na = _single_count",
      "                return out[:found], cnt[:found], True\n            na = _single_count",
      ("tests/test_screen_sizes.py::test_a_cut_list_says_so",)),
    M("screen_cut_list_proves", "designers", "ideas_hpc/design/screen_bound.py",
      "complete = listed and found.shape[0] * k_n <= EXTEND_CAP",
      "complete = found.shape[0] * k_n <= EXTEND_CAP",
      ("tests/test_screen_sizes.py::test_a_cut_screen_gives_a_search_never_a_proof",)),
    M("screen_exact_cut_proves", "designers", "ideas_hpc/design/screen_bound.py",
      "            complete = False\n            break", "            break",
      ("tests/test_screen_sizes.py::test_a_cut_screen_gives_a_search_never_a_proof",)),
    M("pareto_equal_rows_dominate", "designers", "ideas_hpc/design/pareto/nsga2.py",
      "lt = (f[:, None, :] < f[None, :, :]).any(axis=2)",
      "lt = (f[:, None, :] <= f[None, :, :]).any(axis=2)",
      ("tests/test_pareto.py::test_non_dominated_against_brute_force",)),
    M("pareto_repair_separation_narrow", "designers", "ideas_hpc/design/pareto/nsga2.py",
      "free[(i + np.arange(-m, m + 1)) % k] = False",
      "free[(i + np.arange(-m + 1, m)) % k] = False",
      ("tests/test_pareto.py::test_repair_gives_distinct_separated_swarms",)),
    M("requirement_reach_rule_boundary", "designers", "ideas_hpc/mapping/requirement.py",
      "    if reach is not None and reach < 1.0 - eps_tol:\n        return reach",
      "    if reach is not None and reach <= 1.0 - eps_tol:\n        return reach",
      ("tests/test_requirement.py::test_the_reach_rule_is_one_or_the_reach",)),
    M("requirement_meets_without_tolerance", "designers", "ideas_hpc/mapping/requirement.py",
      "    return coverage >= need - COVER_TOL", "    return coverage >= need",
      ("tests/test_requirement.py::test_meets_keeps_the_evaluators_tolerance",)),
    M("requirement_percent_times_hundredth", "designers", "ideas_hpc/base/fields.py",
      "return x / self.per if self.per is not None", "return x * (1 / self.per) if self.per is not None",
      ("tests/test_requirement.py::test_the_percentage_converts_to_the_correctly_rounded_fraction",)),
    M("area_row_asks_the_target", "designers", "ideas_hpc/design/area.py",
      "    return threshold.need + FEAS_TOL", "    return threshold.target + FEAS_TOL",
      ("tests/test_recipe_requirement.py",)),
    # ---- statistics
    M("betting_no_bet_cap", "statistics", "ideas_hpc/design/reliability_stats.py",
      "return np.minimum(lam, 0.75)", "return lam",
      ("tests/test_betting_bound.py::test_bound_on_bernoulli_data_is_near_the_exact_one",)),
    M("betting_alpha_is_confidence", "statistics", "ideas_hpc/design/reliability_stats.py",
      "    alpha = 1.0 - confidence\n    lam = _log_capital", "    alpha = confidence\n    lam = _log_capital",
      ("tests/test_betting_bound.py::test_coverage_at_the_edges",)),
    M("failure_bound_binomial_swapped", "statistics", "ideas_hpc/failures/weights.py",
      "math.comb(n, n - m) * p_f ** (n - m) * (1.0 - p_f) ** m",
      "math.comb(n, n - m) * p_f ** m * (1.0 - p_f) ** (n - m)",
      ("tests/test_betting_bound.py::test_failure_bound_against_enumeration",)),
    M("failures_common_cause", "statistics", "ideas_hpc/failures/sampling.py",
      "if model.beta else u < q", "if model.beta else u[0] < q",
      ("tests/test_dispersions.py::test_failures_are_independent",)),
    M("failures_one_draw_per_scenario", "statistics", "ideas_hpc/montecarlo/failure_dispersion.py",
      "bern = rng.uniform(0.0, 1.0, n)", "bern = rng.uniform(0.0, 1.0)",
      ("tests/test_dispersions.py::test_failures_are_independent",)),
    # ---- the failure model (issue 41)
    M("weights_integer_power_as_float", "statistics", "ideas_hpc/core/design/reliability.py",
      "out[k] = q ** k * p_f ** (n - k)", "out[k] = q ** float(k) * p_f ** float(n - k)",
      ("tests/test_failure_model.py::test_kernel_with_weights_is_the_old_kernel_bit_for_bit",)),
    M("weights_mask_read_by_count", "statistics", "ideas_hpc/core/design/reliability.py",
      "by_mask = weights.size != n + 1", "by_mask = False",
      ("tests/test_failure_model.py::test_per_spacecraft_and_groups_against_brute_force",)),
    M("prior_too_few_nodes", "statistics", "ideas_hpc/failures/prior.py",
      "g = int(degree) // 2 + 1", "g = int(degree) // 6 + 1",
      ("tests/test_failure_model.py::test_beta_prior_weights_are_the_beta_function_ratio",)),
    M("common_cause_not_exclusive", "statistics", "ideas_hpc/failures/weights.py",
      "out += wt * ((1.0 - c) * g + c * (k == 0))", "out += wt * (g + c * (k == 0))",
      ("tests/test_failure_model.py::test_exact_p_against_a_direct_monte_carlo",)),
    M("common_cause_group_least_member", "statistics", "ideas_hpc/failures/weights.py",
      "            c = model.beta * max(q[j] for j in g)\n            indep = np.ones(masks.size)",
      "            c = model.beta * min(q[j] for j in g)\n            indep = np.ones(masks.size)",
      ("tests/test_failure_model.py::test_per_spacecraft_and_groups_against_brute_force",)),
    M("failures_k_ways", "statistics", "ideas_hpc/failures/weights.py",
      "math.comb(n - j, kk) / math.comb(n, kk)", "math.comb(n - j, kk - 1) / math.comb(n, kk)",
      ("tests/test_failure_model.py::test_failures_k_is_the_dispersion_draw",)),
    M("envelope_lightest_set", "statistics", "ideas_hpc/failures/weights.py",
      "np.maximum.at(env, pop, up)", "np.minimum.at(env, pop, up)",
      ("tests/test_failure_model.py::test_upper_law_bounds_p_from_above",)),
    M("in_pass_sure_vertices_not_credited", "statistics", "ideas_hpc/failures/sampling.py",
      "need - float(wk[sure].sum())", "need",
      ("tests/test_failure_model.py::test_upper_law_bounds_p_from_above",)),
    # ---- per-scenario vertex weights (issue 42)
    M("weights_row_always_first", "kernels", "ideas_hpc/core/design/reliability.py",
      "return w2[s if w2.shape[0] > 1 else 0]", "return w2[0]",
      ("tests/test_per_world_weights.py::test_kernel_and_evaluator_match_brute_force_per_scenario",)),
    M("ring_lows_first_world", "designers", "ideas_hpc/design/reliability.py",
      "areas = self.ev.w_of(s)", "areas = self.ev.w_of(0)",
      ("tests/test_per_world_weights.py::test_every_proof_holds_with_weights_by_scenario",)),
    M("scenario_mip_first_world", "designers", "ideas_hpc/design/scenario_mip.py",
      "scenario_groups(rows[s], row(w, s))", "scenario_groups(rows[s], row(w, 0))",
      ("tests/test_per_world_weights.py::test_every_proof_holds_with_weights_by_scenario",)),
    M("tolerance_first_world", "designers", "ideas_hpc/design/tolerance_bound.py",
      "self.solver(self.rows[s], row(self.w, s),", "self.solver(self.rows[s], row(self.w, 0),",
      ("tests/test_per_world_weights.py::test_every_proof_holds_with_weights_by_scenario",)),
    M("validation_first_sample_weights", "statistics", "ideas_hpc/failures/sampling.py",
      "        wk = row(w, k)\n", "        wk = row(w, 0)\n",
      ("tests/test_per_world_weights.py::"
       "test_validation_with_per_sample_weights_and_losses_in_the_pass",)),
    M("enumeration_proves_on_the_score", "designers", "ideas_hpc/design/reliability.py",
      "self.exhausted_upper[n] = float(vals[i]) if self.model.in_pass_share == 0 \\",
      "self.exhausted_upper[n] = float(vals[i]) if True \\",
      ("tests/test_failure_model.py::test_designer_answers_as_exhaustive_search",)),
    M("model_draws_on_the_shared_stream", "statistics",
      "ideas_hpc/montecarlo/failure_dispersion.py",
      "d = draw_failures(failure_model(mc), n, bern, side_rng(rng), perm=perm)",
      "d = draw_failures(failure_model(mc), n, bern, rng, perm=perm)",
      ("tests/test_failure_model.py::test_model_draws_shift_no_other_dispersion",)),
    M("reflectivity_law", "statistics", "ideas_hpc/montecarlo/dispersions.py",
      "lo + (hi - lo) * u", "lo + hi * u",
      ("tests/test_dispersions.py::test_dispersions_have_their_declared_distributions",)),
    M("grs_variance_normalisation", "statistics", "ideas_hpc/body/random_sphere.py",
      "return 4.0 * math.pi * family.beta2 * c / ((2 * ls + 1) * c.sum())",
      "return family.beta2 * c / c.sum()",
      ("tests/test_random_sphere.py::test_log_radius_variance_and_lognormal_mean",)),
    M("mirror_pole_in_equatorial_frame", "statistics", "ideas_hpc/body/spin_prior.py",
      "return np.array([-p[0], -p[1], p[2]])",
      "return DCM_N_EQ @ (np.array([-1.0, -1.0, 1.0]) * (DCM_N_EQ.T @ p))",
      ("tests/test_spin_prior.py::test_mirror_pole_share_and_geometry",)),
    M("mirror_pole_probability_flipped", "statistics", "ideas_hpc/body/spin_prior.py",
      "mirrored = bool(rng.uniform() < self.p_mirror)",
      "mirrored = bool(rng.uniform() > self.p_mirror)",
      ("tests/test_spin_prior.py::test_mirror_pole_share_and_geometry",)),
    M("fisher_kappa_one_over_sigma", "statistics", "ideas_hpc/body/spin_prior.py",
      "return math.inf if self.sigma_rad == 0.0 else 1.0 / self.sigma_rad ** 2",
      "return math.inf if self.sigma_rad == 0.0 else 1.0 / self.sigma_rad",
      ("tests/test_spin_prior.py::test_pole_sigma_is_the_per_axis_spread",)),
    M("phase_sigma_over_period_not_squared", "statistics", "ideas_hpc/body/spin_prior.py",
      "self.sigma_period_s / self.period_s ** 2",
      "self.sigma_period_s / self.period_s",
      ("tests/test_spin_prior.py::test_phase_sigma_formula_and_draws",
       "tests/test_spin_prior.py::test_phase_rule_uniform_above_pi")),
    M("phase_rule_threshold_doubled", "statistics", "ideas_hpc/body/spin_prior.py",
      "return self.sigma_phase_rad > self.uniform_above_rad",
      "return self.sigma_phase_rad > 2.0 * self.uniform_above_rad",
      ("tests/test_spin_prior.py::test_phase_rule_uniform_above_pi",)),
    M("bplane_ellipse_rotated_wrong_way", "statistics", "ideas_hpc/flyby/navigation.py",
      "eta_m=s * u + c * w", "eta_m=-s * u + c * w",
      ("tests/test_navigation.py::test_draws_follow_the_configured_ellipse",)),
    # ---- store
    M("done_flag_before_data", "store", "ideas_hpc/engine/chunk_write.py",
      "    _write_chunk(handles, out, chunk_id, slice(int(start), int(stop)))\n"
      "    _write_chunk(handles, {DONE_VAR: np.ones(1, dtype=bool)}, chunk_id,\n"
      "                 slice(chunk_id, chunk_id + 1))  # last: the chunk is complete\n",
      "    _write_chunk(handles, {DONE_VAR: np.ones(1, dtype=bool)}, chunk_id,\n"
      "                 slice(chunk_id, chunk_id + 1))\n"
      "    _write_chunk(handles, out, chunk_id, slice(int(start), int(stop)))\n",
      ("tests/test_engine_store.py::test_fault_between_writes_never_leaves_a_done_chunk_without_data",)),
    M("done_flag_with_data", "store", "ideas_hpc/engine/chunk_write.py",
      "    _write_chunk(handles, out, chunk_id, slice(int(start), int(stop)))\n",
      "    out[DONE_VAR] = np.ones(1, dtype=bool)\n"
      "    _write_chunk(handles, out, chunk_id, slice(int(start), int(stop)))\n",
      ("tests/test_engine_store.py::test_fault_between_writes_never_leaves_a_done_chunk_without_data",)),
    M("config_hash_key_order", "store", "ideas_hpc/engine/store_meta.py",
      "sort_keys=True, separators", "sort_keys=False, separators",
      ("tests/test_engine_store.py::test_config_hash_is_order_independent_and_sensitive",)),
    M("chunk_plan_drops_last_sample", "store", "ideas_hpc/engine/store_meta.py",
      "return start, min(start + self.chunk_size, self.n_samples)",
      "return start, min(start + self.chunk_size, self.n_samples - 1)",
      ("tests/test_engine_store.py::test_chunk_plan_partitions_samples",)),
    # ---- schema: the keys each kind reads (issue 41)
    M("reads_declaration_dropped", "schema", "ideas_hpc/campaign/schema/kinds.py",
      'COVER + ("design.failures_tolerated", "design.verify_samples",',
      'COVER + ("design.verify_samples",',
      ("tests/test_key_reads_runs.py::test_what_a_run_reads_is_what_its_kind_declares[flyby]",)),
    M("reads_declaration_misses_a_read_key", "schema", "ideas_hpc/campaign/schema/kinds.py",
      'reads=("monte_carlo.samples", DISPERSION_KEYS, "design.eps_tol_pct",\n',
      'reads=("monte_carlo.samples", DISPERSION_KEYS,\n',
      ("tests/test_key_reads_runs.py::test_what_a_run_reads_is_what_its_kind_declares"
       "[monte-carlo]",)),
    M("failures_k_accepted_in_a_success_probability_design", "schema",
      "ideas_hpc/campaign/schema/reads.py",
      "and (FAILURES_K_HONOURED or not s.p)", "",
      ("tests/test_key_reads.py::test_failures_k_in_a_success_probability_design_is_one_switch",)),
    M("reads_judged_only_for_store_configs", "schema",
      "ideas_hpc/campaign/schema/campaign_tables.py",
      "if not source.resolved:", "if source.resolved:",
      ("tests/test_key_reads.py::test_a_stores_resolved_config_is_not_judged",)),
    # ---- the coverage reference (issue 42)
    M("reference_incidence_complement", "kernels", "ideas_hpc/mapping/reference.py",
      "lit &= cos_i >= math.cos(float(max_incidence_rad))",
      "lit &= cos_i >= math.sin(float(max_incidence_rad))",
      ("tests/test_coverage_reference.py::test_a_sphere_lit_fraction_is_the_spherical_cap",)),
    M("reference_shadow_ray_too_short", "kernels", "ideas_hpc/mapping/reference.py",
      "reach = SHADOW_REACH * float(np.max(np.linalg.norm(p, axis=1)))",
      "reach = 0.05 * float(np.max(np.linalg.norm(p, axis=1)))",
      ("tests/test_coverage_reference.py::test_cast_shadows_match_a_brute_force_ray_test",)),
    M("bank_weighs_the_whole_surface", "designers", "ideas_hpc/campaign/design_reliability.py",
      'if c.config.design.coverage_reference != "surface":',
      'if c.config.design.coverage_reference == "none":',
      ("tests/test_coverage_reference_campaign.py::"
       "test_a_success_probability_design_weighs_the_lit_area",)),
    M("exact_design_weighs_the_whole_surface", "designers", "ideas_hpc/campaign/design_exact.py",
      'if requirement.reference != "surface":   # issue 42',
      'if requirement.reference == "none":   # issue 42',
      ("tests/test_coverage_reference_campaign.py::test_a_design_on_the_lit_reference",)),
    M("paper_tca_ignores_spin", "designers", "ideas_hpc/flyby/geometry.py",
      "dp = np.array([d * math.cos(phi), d * math.sin(phi), z1]) - p0",
      "dp = np.array([d, 0.0, z1]) - p0",
      ("tests/test_coverage_reference_campaign.py::"
       "test_the_paper_closest_approach_is_the_trajectory_minimum",)),
    # ---- the failures-only verdict (issue 42)
    M("failures_only_gap_one_sided", "statistics", "ideas_hpc/campaign/failures_only.py",
      '"decides": bool(abs(gap) > half)', '"decides": bool(gap > half)',
      ("tests/test_failures_only.py::"
       "test_the_verdict_is_the_gap_against_the_validation_sampling_error",)),
    M("failures_only_weights_not_normalised", "statistics",
      "ideas_hpc/campaign/failures_only.py",
      "ev = Evaluator(rows, normalised(nominal_bank.areas, 1), need, model)",
      "ev = Evaluator(rows, np.asarray(nominal_bank.areas, dtype=float), need, model)",
      ("tests/test_failures_only.py::test_closed_forms_every_member_needed_and_any_one_enough",)),
    # ---- navigation (SPEC 7f)
    M("nav_start_ignores_the_spin", "kernels", "ideas_hpc/flyby/nav_flight.py",
      "return _r3(phi, o), -_r3(phi, w_x_o)", "return _r3(phi, o), 0.0 * _r3(phi, w_x_o)",
      ("tests/test_navigation_flights.py::"
       "test_the_true_miss_moves_by_the_drawn_bplane_offset_and_tca_shift",)),
    M("nav_tracking_aims_at_the_true_target", "kernels", "ideas_hpc/flyby/nav_flight.py",
      "np.where(lock[..., None], r, r - dr)", "np.where(lock[..., None], r, r + 0.0 * dr)",
      ("tests/test_navigation_flights.py::"
       "test_tracking_the_predicted_target_carries_the_analytic_bias",)),
    M("terminal_lock_ignored_by_the_loop", "kernels", "ideas_hpc/flyby/nav_flight.py",
      "    lock = locked(setup, pos_T)\n    if not lock.any():\n        return track_reference(",
      "    lock = locked(setup, pos_T) & False\n    if not lock.any():\n        return track_reference(",
      ("tests/test_terminal_tracking.py::"
       "test_the_closed_loop_locks_on_the_centroid_and_converges_to_its_error",)),
    M("terminal_centroid_turned_backwards", "kernels", "ideas_hpc/flyby/nav_flight.py",
      "out[i, k, 0:3] = mrp_from_dcm(np.ascontiguousarray(c @ rn))",
      "out[i, k, 0:3] = mrp_from_dcm(np.ascontiguousarray(c.T @ rn))",
      ("tests/test_terminal_tracking.py::"
       "test_the_closed_loop_locks_on_the_centroid_and_converges_to_its_error",)),
    M("terminal_slew_rate_sign", "kernels", "ideas_hpc/flyby/nav_flight.py",
      "np.ascontiguousarray(vel_T - (1.0 - lam) * dv + lam1 * dr)",
      "np.ascontiguousarray(vel_T - (1.0 - lam) * dv - lam1 * dr)",
      ("tests/test_terminal_tracking.py::"
       "test_the_closed_loop_locks_on_the_centroid_and_converges_to_its_error",)),
    M("wheel_torque_limit_loose", "kernels", "ideas_hpc/core/attitude/rigid_body.py",
      "    if v > u_max:\n        v = u_max\n    elif v < -u_max:\n        v = -u_max\n",
      "    if v > 10.0 * u_max:\n        v = 10.0 * u_max\n    elif v < -10.0 * u_max:\n"
      "        v = -10.0 * u_max\n",
      ("tests/test_terminal_tracking.py::"
       "test_images_are_lost_from_where_the_wheels_cannot_follow_the_centroid",)),
    M("encounter_exposure_the_papers", "kernels", "ideas_hpc/flyby/usable.py",
      "return (ENCOUNTER_EXPOSURE_MS if encounter else EXPOSURE_MS) * 1e-3",
      "return (EXPOSURE_MS if encounter else EXPOSURE_MS) * 1e-3",
      ("tests/test_smear.py::test_the_fast_campaigns_expose_for_the_parallax_of_a_tracked_pass",)),
    M("nav_common_error_drawn_per_candidate", "statistics",
      "ideas_hpc/montecarlo/dispersions.py",
      "navigation_dispersion.COMMON_VARS, level=\"body\"",
      "navigation_dispersion.COMMON_VARS, level=\"spacecraft\"",
      ("tests/test_navigation_flights.py::"
       "test_the_common_error_is_shared_by_every_candidate_and_independent_of_chunking",)),
    # ---- start-up (issue 43)
    M("compile_lock_not_held", "store", "ideas_hpc/base/compile_once.py",
      "    with holding(self):\n        return _ORIGINAL(self, sig)",
      "    if True:\n        return _ORIGINAL(self, sig)",
      ("tests/test_compile_once.py::"
       "test_a_process_waits_for_the_kernel_another_compiles_and_loads_it",)),
    M("warm_up_skips_the_bank", "store", "ideas_hpc/campaign/precompile.py",
      "    if bank is not None:\n        warm_bank(setup, *bank)",
      "    if bank is None:\n        warm_bank(setup, *bank)",
      ("tests/test_startup.py::test_the_warm_up_covers_every_kernel_a_bank_worker_runs",)),
)


def _restore(path: Path, text: bytes, stat: os.stat_result) -> None:
    path.write_bytes(text)
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))


def run_one(m: Mutation, python: str, timeout: float) -> tuple[str, float]:
    """Apply ``m``, run its tests, restore; returns (``caught``/``missed``/..., seconds)."""
    path = ROOT / m.path
    original = path.read_bytes()
    stat = path.stat()
    text = original.decode()
    if text.count(m.old) != 1:
        return f"not applied ({text.count(m.old)} matches)", 0.0
    t0 = time.monotonic()
    try:
        path.write_text(text.replace(m.old, m.new))
        cmd = [python, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *m.tests]
        env = dict(os.environ)
        with tempfile.TemporaryDirectory(prefix="mutation-numba-") as cache:
            if m.path.startswith("ideas_hpc/core/"):
                env["NUMBA_CACHE_DIR"] = cache
            try:
                r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True,
                                   timeout=timeout, env=env)
            except subprocess.TimeoutExpired:
                return "caught (timeout)", time.monotonic() - t0
        if r.returncode == 1:
            status = "caught"
        elif r.returncode == 0:
            status = "MISSED"
        else:   # 2-5: collection error, usage, no tests: not a catch by a test
            status = f"error (pytest exit {r.returncode})"
        return status, time.monotonic() - t0
    finally:
        _restore(path, original, stat)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="*", help="mutation names to run (default: all)")
    ap.add_argument("--list", action="store_true", help="print the mutations and exit")
    ap.add_argument("--timeout", type=float, default=1200.0, help="seconds per mutation")
    ap.add_argument("--no-baseline", action="store_true",
                    help="skip the first run of every named test on the unmutated code")
    args = ap.parse_args(argv)
    chosen = [m for m in MUTATIONS if not args.only or m.name in args.only]
    if args.list:
        for m in chosen:
            print(f"{m.area:10s} {m.name:32s} {m.path}  ->  {' '.join(m.tests)}")
        return 0
    if not args.no_baseline:   # a test that already fails would "catch" every mutation
        tests = sorted({t for m in chosen for t in m.tests})
        r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                            *tests], cwd=ROOT, capture_output=True, text=True)
        if r.returncode != 0:
            print(r.stdout[-3000:])
            print("the named tests do not pass on the unmutated code: nothing to measure")
            return 2
        print(f"baseline: the {len(tests)} named tests pass on the unmutated code")
    rows = []
    for m in chosen:
        status, dt = run_one(m, sys.executable, args.timeout)
        rows.append((m, status))
        print(f"| {m.area} | {m.name} | {' '.join(t.split('/')[-1] for t in m.tests)} | "
              f"{status} | {dt:.0f} s |", flush=True)
    bad = [m.name for m, s in rows if not s.startswith("caught")]
    print(f"{len(rows) - len(bad)}/{len(rows)} caught" + (f"; not caught: {bad}" if bad else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())

#!/usr/bin/env python3
"""Renders docs/results.md from docs/results.md.in and the values the tests recorded.

A placeholder `{{module.key}}` or `{{module.key:SPEC}}` in the template is replaced by the value
`key` of `RESULTS_DIR/module.json` (written by the integration tests' `record(key, value)` when
`RIG_RESULTS_DIR` is set; `firmware.json` by `firmware/size.sh`). SPEC is a Python format spec
(`.4f`, `.1e`, `.3g`, `_d`); exponents are written without padding (`9.6e-9`) and the `_`
grouping with spaces (`57 844`). A list is written as its elements, each formatted with SPEC,
joined by ", "; a SPEC starting with a backquote puts each element between backquotes;
`{{module.key|min:SPEC}}` and `|max` write the smallest or largest element of a list, `|len`
its length, `|spaced` its elements joined by spaces. Two prefixes mark values `--check` may not have:
- `~` (`{{~bench.x:.2f}}`): machine- or build-dependent (a time, a memory size, a firmware size
  that moves with the compiler): `--check` does not compare it;
- `^` (`{{^plan_criteria.a_median:.3f}}`): deterministic but recorded only by a slow run outside
  CI (an ignored test, `--run-examples`): compared when the folder holds it, else the committed
  text is kept.
Without a recorded value, `--render` keeps the committed text of a `~` or `^` field.

  python3 scripts/results.py --run [--debug]   run the tests that feed results.md (and size the
                                               firmware when built), render it
  python3 scripts/results.py --run-examples DIR [--debug]
                                               run the plan examples (release; minutes) and the
                                               ignored six-seed test, writing their values to DIR
  python3 scripts/results.py --render DIR      render docs/results.md from the values in DIR
  python3 scripts/results.py --check DIR       render from DIR and compare with the committed
                                               docs/results.md (exit 1 and a diff if it differs)

Standard library only.
"""

import argparse
import difflib
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TEMPLATE = ROOT / "docs" / "results.md.in"
OUTPUT = ROOT / "docs" / "results.md"

# The tests that record the values of the template: (cargo package, test target, test names).
TESTS = [
    (
        "rigctl",
        "integration",
        [
            "calib_synthetic::tilting_reaches_the_noise_floor_and_standard_does_not",
            "calib_ur5::ur5_held_out_mean_beats_the_published_value",
            "calib_normal::katana_normal_equations_match_the_tall_solver",
            "calib_normal::ur5_normal_equations_match_the_tall_solver",
            "calib_convergence::nine_joint_arms_converge_in_one_run",
            "compensate_line::compensated_joints_put_the_calibrated_tilting_arm_on_the_line",
            "compensate_transmission::compensated_joints_through_fk_recover_the_path",
            "model_transmission::transmission_terms_round_trip_through_diagnose_fk_and_calibrate",
            "report_transmission::report_applies_a_model_files_transmission_terms",
            "diagnose_ur5::ur5_laser_tracker_effects_lower_the_held_out_error",
            "diagnose_ur5::ur5_laser_tracker_hybrid_lowers_the_held_out_error",
            "diagnose_transmission::joint_scale_is_named_with_its_ratio",
            "diagnose_transmission::joint_coupling_is_named_with_its_factor",
            "diagnose_transmission::hysteresis_is_named_from_the_pose_order",
            "diagnose_transmission::reported_values_are_the_final_ones",
            "diagnose_thermal::warm_up_is_named_with_its_size_and_time_constant",
            "diagnose_probe::a_bump_in_q2_and_a_q1_q3_interaction_are_both_named",
            "diagnose_probe::pure_noise_false_positive_rate_over_30_seeds",
            "diagnose_verdicts::an_effect_not_added_is_a_missing_effect",
            "diagnose_verdicts::another_tool_mounting_is_a_change_between_sets",
            "diagnose_verdicts::few_poses_for_many_parameters_is_overfitting",
            "tiago_real::figaroh_levels_and_the_press_compliance_model_from_the_cli",
            "tiago_real::four_markers_recover_the_rigid_body_geometry",
            "tiago_real::full_identification_converges_in_one_run",
            "trace_scan::circle_600dpi_rotated_is_within_10um",
            "trace_scan::line_600dpi_rotated_is_within_10um",
            "trace_scan::circle_300dpi_is_within_20um",
            "trace_scan::line_300dpi_is_within_20um",
            "trace_hard::photos_with_tilt_shading_distortion_and_jpeg",
            "trace_hard::photo_12mp_at_35_degrees",
            "trace_hard::scans_600dpi_with_skips_faint_graphite_dust_and_fibres",
            "trace_hard::clean_600dpi_sheet_v2_is_within_5um",
            "trace_hard::page_edge_and_desk_are_not_the_trace",
            "rosbag_joints::a_million_messages_stream_in_bounded_memory",
            "rosbag_joints::fuse_and_fk_from_a_rosbags_bag_equal_the_csv",
            "gross_errors::calibrate_flags_the_gross_errors_of_the_real_ur5_set",
            "gross_errors::clean_sets_flag_almost_nothing",
            "gross_errors::diagnose_flags_the_gross_errors_and_names_the_same_effect",
            "diagnose_sign_steps::payload_steps_are_named_not_flagged_and_blunders_still_are",
            "diagnose_sign_steps::simulated_payload_sessions_keep_the_poses_at_a_switch",
            "diagnose_sign_steps::sets_without_a_payload_flag_no_pose",
            "diagnose_simplest::two_lengths_changed_together_are_named_as_the_pair_not_stand_ins",
            "diagnose_elastic_tilt::an_elastic_tilt_of_joint_1_in_the_arms_plane_is_named_as_the_compliance_of_joint_2",
            "diagnose_lateral::lateral_compliance_of_joint_3_is_named_and_axial_compliance_is_not_taken_for_it",
            "diagnose_changes_independent::this_files_fk_is_rigctls_ur5",
            "diagnose_changes_independent::knocked_tools_and_remounted_markers_are_named_with_their_time",
            "diagnose_changes_independent::a_bumped_instrument_is_seen_by_the_probe",
            "diagnose_changes_independent::sets_without_a_change_false_alarm_rate",
            "model_reference::katana_fk_reference_rows",
            "model_reference::katana_fk_reference_tilt_increments",
            "model_reference::katana_tilt_reference_rows",
            "model_workspace::workspace_matches_wrappers_and_finite_differences",
            "model_workspace::warm_workspace_does_not_allocate",
            "model_workspace::lm_iteration_allocations_do_not_grow_with_the_poses",
            "model_jacobian::katana_jacobian_matches_finite_differences",
            "sim_ik::nominal_round_trip_is_exact_and_prefers_the_seed_branch",
            "calib_normal::ur5_fit_is_a_gauss_newton_fixed_point",
            "joints_fit::recovers_clearance_backlash_and_stiffness_within_three_sigma",
            *(
                "diagnose_sim::" + name
                for name in [
                    "clean_data_adds_nothing",
                    "link_lengths_a2_a3_d5",
                    "link_length_d4_is_absorbed_by_the_declared_parameters",
                    "encoder_harmonics_on_three_joints",
                    "tool_offset",
                    "base_offset",
                    "base_tilt",
                    "payload_and_scale",
                    "tilting_values_stiffness_backlash_clearance",
                    "time_drift",
                    "two_effects_are_both_found",
                    "near_aliases_and_sign_onsets_on_other_seeds",
                ]
            ),
            "diagnose_partial::an_encoder_harmonic_is_named_from_traced_samples",
            "diagnose_partial::a_payload_is_found_through_the_moments",
            "diagnose_partial::clean_traced_samples_add_no_effect_of_any_size",
            "diagnose_probe::pure_noise_gives_nothing",
            "diagnose_probe::katana_smooth_non_physical_error_is_structured_with_the_right_joint",
            "plan_sheets::blind_parameters_of_single_sheets_and_pairs",
            "plan_sim::from_diagnose_separates_an_aliased_pair",
            "plan_sim::diagnose_names_both_effects_after_the_planned_poses",
            "plan_sim::diagnose_still_names_an_encoder_harmonic_and_a_length_after_its_own_aliased_pairs",
            "reliability_streams::defect2_no_subcommand_exits_101_on_closed_or_full_streams",
            "reliability_recording::defect3_one_flipped_byte_costs_one_record_and_is_reported",
            "reliability_values::item2_property_random_finite_values_in_every_model_field",
            "reliability_values::item2_property_random_finite_values_in_every_urdf_number",
            "reliability_loop::the_diagnose_plan_loop_closes_for_every_effect_id",
            "reliability_roundtrip::urdf_joint_names_round_trip",
            "urdf_export::ur5_tracker_after_calibrate_base_in_pinocchio",
            "urdf_export::calibrated_katana_in_pinocchio_names_the_tilting",
            "urdf_export::tiago_round_trip_keeps_the_urdf_and_matches_pinocchio",
            "tree_compliance::tree_compliance_reaches_the_floor_where_geometry_and_chains_do_not",
            "report_first_screen::demo_first_screen_names_the_harmonic",
        ],
    ),
    (
        "rig-tests",
        "e2e",
        [
            "session_e2e::simulated_sessions_calibrate_through_the_cli",
            "session_e2e::an_undeclared_effect_is_diagnosed_from_the_sheets",
        ],
    ),
]

PLACEHOLDER = re.compile(
    r"\{\{([~^]?)([A-Za-z0-9_]+)\.([A-Za-z0-9_]+)(?:\|(min|max|len|spaced))?(?::([^}]*))?\}\}"
)


class RenderError(Exception):
    pass


def load(results_dir):
    """Every `module.json` of `results_dir` as {module: {key: value}}."""
    values = {}
    for path in sorted(Path(results_dir).glob("*.json")):
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
        if not isinstance(doc, dict):
            raise RenderError(f"{path}: not a JSON object")
        values[path.stem] = doc
    return values


def format_one(value, spec):
    """One recorded value as text: a number through the format spec, exponents unpadded."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "null"
    if isinstance(value, str):
        return value
    text = format(value, spec)
    if "_" in spec:
        # 57_844 -> 57 844
        text = text.replace("_", " ")
    # 9.6e-09 -> 9.6e-9, 1.0e+03 -> 1.0e3
    return re.sub(r"e([+-])0*(\d)", lambda m: "e" + m.group(1).replace("+", "") + m.group(2), text)


def format_value(value, spec, sep=", "):
    quote = spec.startswith("`")
    spec = spec[1:] if quote else spec
    items = value if isinstance(value, list) else [value]
    parts = [format_one(v, spec) for v in items]
    if quote:
        parts = [f"`{p}`" for p in parts]
    text = sep.join(parts)
    if "\n" in text:
        raise RenderError(f"a value holds a line break: {text!r}")
    return text


def render_line(line, values, missing, masked=None, kept=None):
    """The line with its placeholders replaced. With `masked` (a list), machine-dependent
    placeholders (and slow-run ones without a recorded value) become regex groups (their indices
    in the line appended to `masked`) and the literal text is escaped: the result is a pattern for
    the committed line. `kept` maps the index of such a placeholder to the committed text used
    when no value was recorded."""

    out, pos = [], 0
    for index, m in enumerate(PLACEHOLDER.finditer(line)):
        lit = line[pos : m.start()]
        out.append(re.escape(lit) if masked is not None else lit)
        pos = m.end()
        tilde, module, key, agg = m.group(1), m.group(2), m.group(3), m.group(4)
        spec = m.group(5) or ""
        name = f"{module}.{key}"
        recorded = key in values.get(module, {})
        if masked is not None and (tilde == "~" or (tilde == "^" and not recorded)):
            out.append("(.+?)")
            masked.append(index)
            continue
        if recorded:
            try:
                value = values[module][key]
                sep = ", "
                if agg:
                    if not isinstance(value, list) or not value:
                        raise RenderError(f"{name}|{agg}: not a non-empty list")
                    if agg == "spaced":
                        sep = " "
                    elif agg == "len":
                        value = len(value)
                    else:
                        value = min(value) if agg == "min" else max(value)
                text = format_value(value, spec, sep)
            except (ValueError, TypeError) as e:
                raise RenderError(f"{name} with spec {spec!r}: {e}") from e
        elif tilde and kept is not None and index in kept:
            text = kept[index]
        else:
            missing.append(name)
            text = m.group(0)
        out.append(re.escape(text) if masked is not None else text)
    tail = line[pos:]
    out.append(re.escape(tail) if masked is not None else tail)
    return "".join(out)


def template_lines():
    return TEMPLATE.read_text(encoding="utf-8").split("\n")


def committed_lines():
    return OUTPUT.read_text(encoding="utf-8").split("\n") if OUTPUT.exists() else []


def compare_line(i, line, values, committed, missing):
    """(whether committed line i matches template line i outside the machine-dependent fields,
    the committed texts of those fields)."""

    masked = []
    pattern = render_line(line, values, missing, masked=masked)
    m = re.fullmatch(pattern, committed[i]) if i < len(committed) else None
    if m is None:
        return False, {}
    return True, dict(zip(masked, m.groups()))


def kept_fields(i, line, values, committed):
    """The committed texts of the machine-dependent fields of template line `i`: from committed
    line `i`, else from any committed line that matches it outside those fields (the committed
    file may have other lines above, e.g. a longer header)."""

    matches, kept = compare_line(i, line, values, committed, [])
    if not matches and ("{{~" in line or "{{^" in line):
        for j in range(len(committed)):
            matches, kept = compare_line(j, line, values, committed, [])
            if matches:
                break
    return kept


def render(values):
    """The rendered text; a machine-dependent field without a recorded value keeps the text of
    the committed results.md."""

    committed, missing, out = committed_lines(), [], []
    for i, line in enumerate(template_lines()):
        kept = kept_fields(i, line, values, committed)
        out.append(render_line(line, values, missing, kept=kept))
    if missing:
        raise RenderError("no recorded value for: " + ", ".join(sorted(set(missing))))
    return "\n".join(out)


def check(values):
    """0 when the committed results.md equals the rendering outside the machine-dependent
    fields, else 1 after a unified diff."""

    committed, lines = committed_lines(), template_lines()
    same = len(committed) == len(lines)
    missing, shown = [], []
    for i, line in enumerate(lines):
        matches, _ = compare_line(i, line, values, committed, missing)
        if matches:
            shown.append(committed[i])
        else:
            same = False
            kept = kept_fields(i, line, values, committed)
            shown.append(render_line(line, values, [], kept=kept))
    if missing:
        print(
            "results.py: no recorded value for: " + ", ".join(sorted(set(missing))),
            file=sys.stderr,
        )
        return 1
    if same:
        print(f"results.py: {OUTPUT.relative_to(ROOT)} matches the recorded values")
        return 0
    diff = difflib.unified_diff(
        committed,
        shown,
        fromfile=f"{OUTPUT.relative_to(ROOT)} (committed)",
        tofile=f"{OUTPUT.relative_to(ROOT)} (rendered; machine-dependent fields as committed)",
        lineterm="",
    )
    print("\n".join(diff))
    print(
        "results.py: docs/results.md differs from the recorded values; regenerate it with "
        "`python3 scripts/results.py --run` (or --render DIR) and commit it",
        file=sys.stderr,
    )
    return 1


def run_tests(results_dir, debug):
    if results_dir.exists():
        shutil.rmtree(results_dir)
    results_dir.mkdir(parents=True)
    env = dict(os.environ, RIG_RESULTS_DIR=str(results_dir))
    for package, target, names in TESTS:
        cmd = ["cargo", "test", "-p", package]
        if not debug:
            cmd.append("--release")
        cmd += ["--test", target, "--", "--exact", *names]
        print("+", " ".join(cmd), file=sys.stderr)
        subprocess.run(cmd, cwd=ROOT, env=env, check=True)
    # the firmware sizes, when the firmware has been built (.ci/run builds it; `~` fields)
    elf = ROOT / "firmware" / "target" / "thumbv7em-none-eabihf" / "release" / "rig-firmware"
    if elf.exists():
        subprocess.run(["bash", "firmware/size.sh"], cwd=ROOT, env=env, check=True)
    else:
        print(f"results.py: {elf.relative_to(ROOT)} not built: firmware sizes kept", file=sys.stderr)


# The slow runs behind the Plan tables (`^` fields): (results module, cargo example, its
# arguments), each printing the Markdown table the template renders from.
EXAMPLES = [
    ("plan_criteria", "plan_criteria", ["12", "8", "5000", "1", "3", "1", "agid", "400"]),
    ("plan_curve", "plan_curve", ["docs/plan_heldout.svg", "gai"]),
    ("plan_real_ur5", "plan_real_ur5", ["agid", "50"]),
]
# The ignored test behind the six-seed table of `--from-diagnose` (records `plan_sim.six_seeds_*`).
SLOW_TESTS = [("rigctl", "integration", ["plan_sim::six_seeds_of_the_payload_case"])]


def table_rows(text):
    """The cells of the Markdown table rows of `text` (header and separator left out)."""
    rows = []
    for line in text.splitlines():
        line = line.strip()
        if not line.startswith("|") or set(line) <= set("|-: "):
            continue
        rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows[1:] if rows else []


def numbers(cell):
    """The numbers of a table cell: `0.564 / 0.642 / 0.716` -> [0.564, 0.642, 0.716]."""
    return [float(x) for x in re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", cell)]


def parse_plan_criteria(text):
    """`plan_criteria`'s stdout: per criterion letter C, `C_ratios` (per seed), `C_median`,
    `C_worst`, `C_p10` / `C_p50` / `C_p90` (against single draws), `C_direct_median` /
    `C_direct_worst` (mean draw), `C_condition`, and from the line after the row
    `C_optimum_ratios`, `C_optimum_median`, `C_efficiency_median`, `C_efficiency_min`."""
    values, current = {}, None
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("|") and len(cells) == 8 and len(cells[0]) == 1:
            c = current = cells[0]
            values[f"{c}_ratios"] = numbers(cells[1])
            values[f"{c}_median"], values[f"{c}_worst"] = numbers(cells[2])[0], numbers(cells[3])[0]
            values[f"{c}_p10"], values[f"{c}_p50"], values[f"{c}_p90"] = numbers(cells[4])
            values[f"{c}_direct_median"], values[f"{c}_direct_worst"] = numbers(cells[5])
            values[f"{c}_condition"] = numbers(cells[7])[0]
        elif current and line.strip().startswith("best possible"):
            m = re.search(r"per seed ([\d. ]+) \(median ([\d.]+)\); plan efficiency median ([\d.]+), min ([\d.]+)", line)
            if not m:
                raise RenderError(f"plan_criteria: cannot read {line!r}")
            values[f"{current}_optimum_ratios"] = numbers(m.group(1))
            values[f"{current}_optimum_median"] = float(m.group(2))
            values[f"{current}_efficiency_median"] = float(m.group(3))
            values[f"{current}_efficiency_min"] = float(m.group(4))
    return values


def parse_n_table(text):
    """A table with one row per N (`plan_curve`, `plan_real_ur5`): `n<N>_<column>`, the column
    named by its header (`planned a (mm)` -> `a`, `random median (mm)` -> `random_median`,
    `random p10 / p90 (mm)` -> `random_p10`, `random_p90`)."""
    header = None
    values = {}
    for line in text.splitlines():
        if not line.startswith("|"):
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells[0] == "N":
            header = []
            for h in cells[1:]:
                h = re.sub(r"\s*\(mm\)$", "", h).replace("planned ", "")
                if "/" in h:
                    stem = h.split()[0]
                    header += [f"{stem}_{w.strip().split()[-1]}" for w in h.split("/")]
                else:
                    header.append(re.sub(r"\W+", "_", h).strip("_"))
            continue
        if header is None or not cells[0].isdigit():
            continue
        nums = [x for c in cells[1:] for x in numbers(c)]
        if len(nums) != len(header):
            raise RenderError(f"cannot read the row {line!r} under {header}")
        for name, v in zip(header, nums):
            values[f"n{cells[0]}_{name}"] = v
    m = re.search(r"full (\d+) grid poses: held-out mean ([\d.]+) mm", text)
    if m:
        values["full_grid_poses"], values["full_grid_mm"] = int(m.group(1)), float(m.group(2))
    return values


def run_examples(results_dir, debug=False):
    """Runs the plan examples (release, or the test profile with `debug`) and the ignored
    six-seed test; writes their values to `results_dir` (merged with what is there)."""
    results_dir.mkdir(parents=True, exist_ok=True)
    profile = ["--profile", "test"] if debug else ["--release"]
    for module, example, args in EXAMPLES:
        cmd = ["cargo", "run", *profile, "--locked", "-p", "rigctl", "--example", example, "--", *args]
        print("+", " ".join(cmd), file=sys.stderr)
        out = subprocess.run(cmd, cwd=ROOT, check=True, stdout=subprocess.PIPE, text=True).stdout
        sys.stdout.write(out)
        values = parse_plan_criteria(out) if module == "plan_criteria" else parse_n_table(out)
        if not values:
            raise RenderError(f"{example}: no table in its output")
        path = results_dir / f"{module}.json"
        doc = json.loads(path.read_text(encoding="utf-8")) if path.exists() else {}
        doc.update(values)
        path.write_text(json.dumps(doc, indent=2, sort_keys=True) + "\n", encoding="utf-8")
    env = dict(os.environ, RIG_RESULTS_DIR=str(results_dir))
    for package, target, names in SLOW_TESTS:
        cmd = ["cargo", "test", *([] if debug else ["--release"]), "-p", package, "--test", target, "--",
               "--exact", "--ignored", *names]
        print("+", " ".join(cmd), file=sys.stderr)
        subprocess.run(cmd, cwd=ROOT, env=env, check=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--run", action="store_true", help="run the tests, then render")
    mode.add_argument("--run-examples", metavar="DIR",
                      help="run the plan examples and the slow test, writing their values to DIR")
    mode.add_argument("--render", metavar="DIR", help="render from the values in DIR")
    mode.add_argument("--check", metavar="DIR", help="compare the rendering from DIR with results.md")
    ap.add_argument("--debug", action="store_true",
                    help="with --run or --run-examples: the test profile instead of release")
    args = ap.parse_args()
    try:
        if args.check:
            return check(load(args.check))
        if args.run_examples:
            try:
                run_examples(Path(args.run_examples).resolve(), args.debug)
            except subprocess.CalledProcessError as e:
                print(f"results.py: {e}", file=sys.stderr)
                return 1
            print(f"results.py: wrote the plan values to {args.run_examples}; render with "
                  f"--render (after --run, whose folder is target/results-run)")
            return 0
        if args.run:
            results_dir = ROOT / "target" / "results-run"
            try:
                run_tests(results_dir, args.debug)
            except subprocess.CalledProcessError as e:
                print(f"results.py: {e}", file=sys.stderr)
                return 1
            values = load(results_dir)
        else:
            values = load(args.render)
        text = render(values)
        OUTPUT.write_text(text, encoding="utf-8")
        print(f"results.py: wrote {OUTPUT.relative_to(ROOT)}")
        return 0
    except (RenderError, OSError, json.JSONDecodeError) as e:
        print(f"results.py: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

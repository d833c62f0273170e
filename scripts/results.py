#!/usr/bin/env python3
"""Renders docs/results.md from docs/results.md.in and the values the tests recorded.

A placeholder `{{module.key}}` or `{{module.key:SPEC}}` in the template is replaced by the value
`key` of `RESULTS_DIR/module.json` (written by the integration tests' `record(key, value)` when
`RIG_RESULTS_DIR` is set). SPEC is a Python format spec (`.4f`, `.1e`, `.3g`); exponents are
written without padding (`9.6e-9`). A list is written as its elements, each formatted with SPEC,
joined by ", "; a SPEC starting with a backquote puts each element between backquotes;
`{{module.key|min:SPEC}}` and `|max` write the smallest or largest element of a list. A
placeholder starting with `~` (`{{~bench.x:.2f}}`) is machine-dependent (a time, a memory size):
`--check` does not compare it.

  python3 scripts/results.py --run [--debug]   run the tests that feed results.md, render it
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
        ],
    ),
]

PLACEHOLDER = re.compile(
    r"\{\{(~?)([A-Za-z0-9_]+)\.([A-Za-z0-9_]+)(?:\|(min|max))?(?::([^}]*))?\}\}"
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
    # 9.6e-09 -> 9.6e-9, 1.0e+03 -> 1.0e3
    return re.sub(r"e([+-])0*(\d)", lambda m: "e" + m.group(1).replace("+", "") + m.group(2), text)


def format_value(value, spec):
    quote = spec.startswith("`")
    spec = spec[1:] if quote else spec
    items = value if isinstance(value, list) else [value]
    parts = [format_one(v, spec) for v in items]
    if quote:
        parts = [f"`{p}`" for p in parts]
    text = ", ".join(parts)
    if "\n" in text:
        raise RenderError(f"a value holds a line break: {text!r}")
    return text


def render_line(line, values, missing, masked=None, kept=None):
    """The line with its placeholders replaced. With `masked` (a list), machine-dependent
    placeholders become regex groups (their names appended to `masked`) and the literal text is
    escaped: the result is a pattern for the committed line. `kept` maps the name of a
    machine-dependent placeholder to the committed text used when no value was recorded."""

    out, pos = [], 0
    for m in PLACEHOLDER.finditer(line):
        lit = line[pos : m.start()]
        out.append(re.escape(lit) if masked is not None else lit)
        pos = m.end()
        tilde, module, key, agg = m.group(1), m.group(2), m.group(3), m.group(4)
        spec = m.group(5) or ""
        name = f"{module}.{key}"
        if tilde and masked is not None:
            out.append("(.+?)")
            masked.append(name)
            continue
        if key in values.get(module, {}):
            try:
                value = values[module][key]
                if agg:
                    if not isinstance(value, list) or not value:
                        raise RenderError(f"{name}|{agg}: not a non-empty list")
                    value = min(value) if agg == "min" else max(value)
                text = format_value(value, spec)
            except (ValueError, TypeError) as e:
                raise RenderError(f"{name} with spec {spec!r}: {e}") from e
        elif tilde and kept is not None and name in kept:
            text = kept[name]
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
    if not matches and "{{~" in line:
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


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--run", action="store_true", help="run the tests, then render")
    mode.add_argument("--render", metavar="DIR", help="render from the values in DIR")
    mode.add_argument("--check", metavar="DIR", help="compare the rendering from DIR with results.md")
    ap.add_argument("--debug", action="store_true", help="with --run: the test profile instead of release")
    args = ap.parse_args()
    try:
        if args.check:
            return check(load(args.check))
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

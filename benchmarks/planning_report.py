"""The planning benchmark's figures per class of problems, issues 16 and 27's targets, the table,
and the comparison with VAMP.

Everything here works on the per-problem records that benchmarks/planning.py writes
to its JSON, so a saved run can be summarised again.

VAMP (``vamp-planner`` 0.6.4) does not build on this machine: its CMake downloads
CPM.cmake and then ``kavrakilab/nigh`` from GitHub, and there is no network here
(``pip install vamp-planner`` fails at "CMake configuration failed"). So the comparison
uses its figures published in issue 27 (:data:`VAMP_PUBLISHED`), measured from outside
on 100 single-Panda problems in a scene both planners represent exactly (a table, a
five-board shelf, three posts, two balls; 300 requests), on this kind of 2-core machine:
another problem set than the shared cell's, so the ratios compare orders of magnitude,
not problem by problem. The report says so wherever it prints them.
"""

from __future__ import annotations

import collections
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

#: Phases of a request, in the order they run (``Plan.seconds``).
PHASES = ("scene", "ik", "check", "search", "simplify", "certify", "timing", "in_time")
#: Phases made of collision checks (and the search's sampling).
CHECKING = ("check", "search", "simplify", "certify")
#: Issue 27's targets for the CPU time of a whole request [ms], per class (the p95 of two
#: arms is issue 16's); success within 1 s.
MEDIAN_TARGET_MS = {"1 arm": 3.0, "2 arms": 10.0}
P95_TARGET_MS = {"1 arm": 15.0, "2 arms": 100.0}
SUCCESS_TARGET = 0.99
#: Issue 27: executed duration at most this share of rest-to-rest on the same waypoints.
DURATION_RATIO_TARGET = 0.7
STRAIGHT_COLLISION_TARGET = 0.5

Record = dict[str, Any]


def _stat(values: Sequence[float], q: float) -> float | None:
    return round(float(np.percentile(values, q)), 3) if values else None


def _rate(part: int, whole: int) -> float | None:
    return round(part / whole, 4) if whole else None


def class_row(records: Sequence[Record]) -> dict[str, Any]:
    """The figures of one class of problems."""
    attempted = [r for r in records if r["attempted"]]
    solved = [r for r in attempted if r["solved"]]
    times = [r["request_ms"] for r in solved]
    cpu = [r.get("request_cpu_ms", 0.0) for r in solved]
    durations = [r["duration_s"] for r in solved if r.get("duration_s") is not None]
    ratios = [
        r["duration_s"] / r["rest_to_rest_s"]
        for r in solved
        if r.get("duration_s") is not None and r.get("rest_to_rest_s")
    ]
    total_ms = sum(times)
    phase_sums = {k: sum(r["phases_ms"].get(k, 0.0) for r in solved) for k in PHASES}
    pose = [r for r in attempted if r["goal"] == "pose"]
    straight = [r for r in records if not r["straight"]["refused"]]
    failures = collections.Counter(r["reason"] or "unknown" for r in records if not r["solved"])
    tracking = [r["tracking_error_rad"] * 1e3 for r in solved]
    return {
        "problems": len(records),
        "attempted": len(attempted),
        "solved": len(solved),
        "success_rate": _rate(len(solved), len(attempted)),
        "solved_within_1s": sum(r["request_ms"] <= 1000.0 for r in solved),
        "pose_goal_problems": len(pose),
        "pose_goal_solved": sum(r["solved"] for r in pose),
        "failures": dict(failures),
        "request_ms": {
            "median": _stat(times, 50),
            "p95": _stat(times, 95),
            "max": round(max(times), 3) if times else None,
        },
        "request_cpu_ms": {
            "median": _stat(cpu, 50),
            "p95": _stat(cpu, 95),
            "max": round(max(cpu), 3) if cpu else None,
        },
        "duration_s": {
            "median": _stat(durations, 50),
            "rest_to_rest_median": _stat(
                [r["rest_to_rest_s"] for r in solved if r.get("rest_to_rest_s")], 50
            ),
            # executed / rest to rest on the same waypoints: below 1 is shorter
            "ratio_median": _stat(ratios, 50),
            "ratio_max": round(max(ratios), 4) if ratios else None,
        },
        "planner_ms_median": _stat([r["planner_ms"] for r in solved], 50),
        "phase_ms_median": {
            k: _stat([r["phases_ms"].get(k, 0.0) for r in solved], 50) for k in PHASES
        },
        "time_share": {k: _rate_f(v, total_ms) for k, v in phase_sums.items()}
        | {"other": _rate_f(total_ms - sum(phase_sums.values()), total_ms)},
        "checks_median": _stat([r["checks"] for r in solved], 50),
        # Upper bound of one check's cost: the phases that check states, over the checks.
        "us_per_check_median": _stat(
            [
                sum(r["phases_ms"].get(k, 0.0) for k in CHECKING) * 1e3 / r["checks"]
                for r in solved
                if r["checks"]
            ],
            50,
        ),
        "scene_build_ms_median": _stat([r["scene_build_ms"] for r in attempted], 50),
        "samples_median": _stat([r["samples"] for r in solved], 50),
        "straight_line_proven_clear": sum(r["straight_clear"] for r in solved),
        "length_ratio": {
            "median": _stat([r["length_ratio"] for r in solved], 50),
            "p95": _stat([r["length_ratio"] for r in solved], 95),
            "max": max((r["length_ratio"] for r in solved), default=None),
        },
        "recheck_touching_paths": sum(bool(r["recheck_touches"]) for r in solved),
        "execution": {
            "motions": len(solved),
            "motions_with_contacts": sum(r["contact_steps"] > 0 for r in solved),
            "contact_steps": sum(r["contact_steps"] for r in solved),
            "protective_stops": sum(r["stops"] for r in solved),
            "deepest_mm": max((r["deepest_mm"] for r in solved), default=0.0),
            "tracking_error_mrad_median": _stat(tracking, 50),
            "tracking_error_mrad_max": round(max(tracking), 4) if tracking else None,
            "pose_error_mm_max": max(
                (r["pose_error_mm"] for r in solved if r["pose_error_mm"] is not None),
                default=None,
            ),
            "pose_error_deg_max": max(
                (r["pose_error_deg"] for r in solved if r["pose_error_deg"] is not None),
                default=None,
            ),
        },
        "straight": {
            "motions": len(straight),
            "refused": len(records) - len(straight),
            "collided": sum(r["straight_collided"] for r in straight),
            "collision_rate": _rate(sum(r["straight_collided"] for r in straight), len(straight)),
            "protective_stops": sum(r["straight"]["stops"] for r in straight),
        },
    }


def _rate_f(part: float, whole: float) -> float | None:
    return round(part / whole, 4) if whole > 0 else None


def summarise(records: Sequence[Record]) -> dict[str, dict[str, Any]]:
    """Per class (``"1 arm"``, ``"2 arms"``) and for ``"all"``."""
    kinds = sorted({r["kind"] for r in records})
    rows = {kind: class_row([r for r in records if r["kind"] == kind]) for kind in kinds}
    rows["all"] = class_row(records)
    return rows


def targets(classes: dict[str, dict[str, Any]]) -> list[dict[str, Any]]:
    """Issues 16's and 27's targets, each with the measured value and whether it is met."""
    out: list[dict[str, Any]] = []

    def add(what: str, value: Any, met: bool) -> None:
        out.append({"target": what, "value": value, "met": bool(met)})

    for kind, row in classes.items():
        if kind == "all":
            continue
        attempted = row["attempted"]
        within = row["solved_within_1s"] / attempted if attempted else 0.0
        success = f"{kind}: success within 1 s >= {SUCCESS_TARGET:.0%}"
        add(success, round(within, 4), within >= SUCCESS_TARGET)
        median, p95 = row["request_cpu_ms"]["median"], row["request_cpu_ms"]["p95"]
        goal = MEDIAN_TARGET_MS.get(kind, MEDIAN_TARGET_MS["2 arms"])
        add(f"{kind}: CPU median <= {goal:g} ms", median, median is not None and median <= goal)
        high = P95_TARGET_MS.get(kind, P95_TARGET_MS["2 arms"])
        add(f"{kind}: CPU p95 <= {high:g} ms", p95, p95 is not None and p95 <= high)
    ratio = classes["all"]["duration_s"]["ratio_median"]
    shorter = ratio is not None and ratio <= DURATION_RATIO_TARGET
    add(f"executed / rest-to-rest duration <= {DURATION_RATIO_TARGET:g}", ratio, shorter)
    execution = classes["all"]["execution"]
    clean = execution["contact_steps"] == 0 and execution["protective_stops"] == 0
    add("0 contacts (and 0 stops) during execution", execution["contact_steps"], clean)
    touching = classes["all"]["recheck_touching_paths"]
    add("returned paths touching at the independent re-check: 0", touching, touching == 0)
    rate = classes["all"]["straight"]["collision_rate"]
    enough = rate is not None and rate >= STRAIGHT_COLLISION_TARGET
    add(f"straight move_together collides on >= {STRAIGHT_COLLISION_TARGET:.0%}", rate, enough)
    return out


#: VAMP's figures in issue 27: vamp-planner 0.6.4, plan + simplify, CPU time per problem,
#: 100 single-Panda problems (300 requests) in its own scene; paths touching the real
#: meshes re-checked in PyBullet every 1e-3 rad.
VAMP_PUBLISHED: dict[str, Any] = {
    "source": "published in issue 27 (vamp-planner 0.6.4 does not build here: its CMake "
    "fetches CPM.cmake and kavrakilab/nigh from GitHub; no network)",
    "problems": "100 single-Panda problems (300 requests), table + shelf + posts + balls",
    "cpu_ms": {"median": 0.88, "p95": 4.14, "max": 7.65},
    "solved": [300, 300],
    "touching": [36, 100],
    "two_arms_cpu_ms_median": 1.42,
}


def vamp_comparison(classes: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """armfleet's CPU time per request, solved and touching paths, beside VAMP's published
    figures (:data:`VAMP_PUBLISHED`), with the ratios armfleet / VAMP."""
    vamp = VAMP_PUBLISHED
    one, two = classes.get("1 arm"), classes.get("2 arms")
    ours: dict[str, Any] = {}
    if one is not None:
        cpu = one["request_cpu_ms"]
        ours = {
            "cpu_ms": cpu,
            "solved": [one["solved"], one["attempted"]],
            "touching": [one["recheck_touching_paths"], one["solved"]],
            "cpu_ratio": {
                k: None if cpu[k] is None else round(cpu[k] / vamp["cpu_ms"][k], 2)
                for k in ("median", "p95", "max")
            },
        }
    if two is not None and two["request_cpu_ms"]["median"] is not None:
        median = two["request_cpu_ms"]["median"]
        ours["two_arms_cpu_ms_median"] = median
        ours["two_arms_cpu_ratio"] = round(median / vamp["two_arms_cpu_ms_median"], 2)
    return {"vamp": vamp, "armfleet": ours}


def print_vamp(comparison: dict[str, Any]) -> None:
    """The comparison table, with where VAMP's figures come from."""
    vamp, ours = comparison["vamp"], comparison["armfleet"]
    if not ours:
        return
    print(
        f"\nagainst VAMP, one Panda; VAMP's figures {vamp['source']}; its problems: "
        f"{vamp['problems']} (not the shared cell's: compare orders of magnitude)"
    )

    def triple(d: dict[str, Any]) -> str:
        return " / ".join("-" if d[k] is None else f"{d[k]:.2f}" for k in ("median", "p95", "max"))

    def ratio(d: dict[str, Any]) -> str:
        return " / ".join("-" if d[k] is None else f"{d[k]:.1f}x" for k in d)

    rows = [
        ("", "VAMP (plan + simplify)", "armfleet whole request", "armfleet / VAMP"),
        ("CPU ms median / p95 / max", triple(vamp["cpu_ms"]), triple(ours["cpu_ms"]),
         ratio(ours["cpu_ratio"])),
        ("solved", "{}/{}".format(*vamp["solved"]), "{}/{}".format(*ours["solved"]), ""),
        ("paths touching", "{}/{}".format(*vamp["touching"]), "{}/{}".format(*ours["touching"]),
         ""),
    ]  # fmt: skip
    if "two_arms_cpu_ms_median" in ours:
        rows.append(
            ("two arms, CPU ms median", f"{vamp['two_arms_cpu_ms_median']} (Baxter)",
             _ms(ours["two_arms_cpu_ms_median"]), f"{ours['two_arms_cpu_ratio']:.0f}x")
        )  # fmt: skip
    widths = [max(len(row[i]) for row in rows) for i in range(4)]
    for row in rows:
        print("  ".join(text.ljust(width) for text, width in zip(row, widths, strict=True)))


def _ms(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f}"


def _table_rows(phases: Sequence[str]) -> list[tuple[str, Callable[[dict[str, Any]], str]]]:
    """Label and cell of each line of the table."""

    def request(r: dict[str, Any]) -> str:
        return " / ".join(_ms(r["request_ms"][k]) for k in ("median", "p95", "max"))

    def cpu(r: dict[str, Any]) -> str:
        return " / ".join(_ms(r["request_cpu_ms"][k]) for k in ("median", "p95", "max"))

    def duration(r: dict[str, Any]) -> str:
        d = r["duration_s"]
        ratio = "-" if d["ratio_median"] is None else f"{d['ratio_median']:.2f}"
        return f"{_round(d['median'])} / {_round(d['rest_to_rest_median'])} ({ratio})"

    def phase(name: str) -> Callable[[dict[str, Any]], str]:
        return lambda r: f"{_ms(r['phase_ms_median'][name])} ({r['time_share'][name] or 0:.0%})"

    def execution(r: dict[str, Any]) -> str:
        e = r["execution"]
        return f"{e['motions_with_contacts']} ({e['contact_steps']}) / {e['protective_stops']}"

    def tracking(r: dict[str, Any]) -> str:
        e = r["execution"]
        return f"{_round(e['tracking_error_mrad_median'])} / {_round(e['tracking_error_mrad_max'])}"

    def pose_error(r: dict[str, Any]) -> str:
        e = r["execution"]
        return f"{_round(e['pose_error_mm_max'])} / {_round(e['pose_error_deg_max'])}"

    def straight(r: dict[str, Any]) -> str:
        s = r["straight"]
        if not s["motions"]:
            return "-"
        return f"{s['collided']}/{s['motions']} ({s['collision_rate']:.0%})"

    rows: list[tuple[str, Callable[[dict[str, Any]], str]]] = [
        ("solved / attempted (problems)",
         lambda r: f"{r['solved']}/{r['attempted']} ({r['problems']})"),
        ("  pose goals solved", lambda r: f"{r['pose_goal_solved']}/{r['pose_goal_problems']}"),
        ("  failures", lambda r: ", ".join(f"{k}: {v}" for k, v in r["failures"].items()) or "-"),
        ("request ms median / p95 / max", request),
        ("request CPU ms median / p95 / max", cpu),
    ]  # fmt: skip
    rows += [(f"  {name} ms median (share)", phase(name)) for name in phases]
    rows += [
        ("  other (share)", lambda r: f"{r['time_share']['other'] or 0:.0%}"),
        ("collision checks / samples median",
         lambda r: f"{r['checks_median']} / {r['samples_median']}"),
        ("  us per check median (upper bound)", lambda r: str(r["us_per_check_median"])),
        ("scene build after respawn ms median", lambda r: str(r["scene_build_ms_median"])),
        ("straight line proven clear", lambda r: str(r["straight_line_proven_clear"])),
        ("length / straight line med / p95",
         lambda r: f"{r['length_ratio']['median']} / {r['length_ratio']['p95']}"),
        ("independent re-check: touching", lambda r: str(r["recheck_touching_paths"])),
        ("executed s / rest-to-rest s med (ratio)", duration),
        ("execution: contacts (steps) / stops", execution),
        ("tracking error mrad med / max", tracking),
        ("pose error max mm / deg", pose_error),
        ("STRAIGHT move_together: collided", straight),
        ("  straight: stops / refused",
         lambda r: f"{r['straight']['protective_stops']} / {r['straight']['refused']}"),
    ]  # fmt: skip
    return rows


def _round(value: float | None) -> str:
    return "-" if value is None else f"{value:.3g}"


def print_report(figures: dict[str, Any]) -> None:
    """The table (one column per class), then the targets with met / MISS."""
    settings, classes = figures["settings"], figures["classes"]
    limit = (
        f"budget {settings['budget']} iterations"
        if "budget" in settings
        else f"timeout {settings['timeout_s']} s"
    )
    print(
        f"\nshared cell, {settings['problems']} problems (seed {settings['seed']}, every "
        f"{settings['pose_goals_every']}rd with pose goals), {limit}, "
        f"clearance {settings['clearance_m'] * 1e3:g} mm; machine load "
        f"{' -> '.join(map(str, settings['load_average_1min']))} (1 min, before -> after)"
    )
    lines: list[tuple[str, ...]] = [("", *classes)]
    for label, cell in _table_rows(PHASES):
        lines.append((label, *(cell(row) for row in classes.values())))
    widths = [max(len(line[i]) for line in lines) for i in range(len(lines[0]))]
    for line in lines:
        print("  ".join(text.ljust(width) for text, width in zip(line, widths, strict=True)))
    print("\ntargets:")
    for target in figures["targets"]:
        print(f"  {'met ' if target['met'] else 'MISS'}  {target['target']}: {target['value']}")
    if "vamp" in figures:
        print_vamp(figures["vamp"])

#!/usr/bin/env python3
"""Runs the hard-case suite (hard_cases.py): every case of config/scenes/hard/ on the track models where it
means something, plus a refined run for the convergence check; prints one line per run and case, writes
results.yaml into --out and, with --docs, the results table into that Markdown file (the text above its
marker line is kept). Exit 0 when every check passes, 1 when one fails, 2 on a usage error.

  scripts/hard_cases/run_hard_cases.py [--subset ci|all] [--models rigid,rigid_fe,flexible] [--jobs N]
                                       [--out DIR] [--docs docs/hard_cases.md] [--workspace WS] [--timeout S]
                                       [--cases KEY,...]

--workspace: the built catkin workspace whose nodes and launch files run the scenes (default: this
repository); the scenes and data files are always this repository's.
"""
import argparse
import os
import signal
import sys

import yaml

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import hard_cases  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(prog="run_hard_cases.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("--subset", choices=("ci", "all"), default="all")
    ap.add_argument("--models", default=",".join(hard_cases.MODELS))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default=os.path.join("output", "hard_cases"))
    ap.add_argument("--docs", help="Markdown file to write the results table into (e.g. docs/hard_cases.md)")
    ap.add_argument("--workspace", default=hard_cases.REPO)
    ap.add_argument("--cases", help="comma-separated case keys to (re)run; the subset's other runs are "
                    "evaluated from their results already in --out")
    ap.add_argument("--timeout", type=float, default=900.0, help="wall seconds per run (default 900)")
    a = ap.parse_args(argv)
    models = [m.strip() for m in a.models.split(",") if m.strip()]
    bad = [m for m in models if m not in hard_cases.MODELS]
    if bad or not models:
        print("run_hard_cases.py: --models: unknown model '%s' (known: %s)" % (
            (bad or [""])[0], ", ".join(hard_cases.MODELS)), file=sys.stderr)
        return 2
    if a.jobs < 1:
        print("run_hard_cases.py: --jobs: must be >= 1, got %d" % a.jobs, file=sys.stderr)
        return 2

    def on_signal(signum, frame):
        raise KeyboardInterrupt()
    signal.signal(signal.SIGTERM, on_signal)
    try:
        rows, total = hard_cases.run_suite(a.subset, models, a.jobs, a.out, os.path.abspath(a.workspace), a.timeout,
                                           progress=lambda s: print(s, flush=True),
                                           only=[k.strip() for k in a.cases.split(",")] if a.cases else None)
    except KeyboardInterrupt:
        print("run_hard_cases.py: interrupted", file=sys.stderr)
        return 130
    failed = 0
    summary = []
    for row in rows:
        ok = hard_cases.row_passed(row)
        failed += not ok
        ev = row["eval"]
        print("%-26s %-9s %s" % (row["case"].key, row["model"], "pass" if ok else "FAIL"))
        for n, st, txt in ev["checks"]:
            print("    %-5s %s: %s" % (st, n, txt))
        print("    %-5s convergence of %s: %s" % (ev["converge"][0], row["case"].key_figure[0], ev["converge"][1]))
        summary.append({"case": row["case"].key, "model": row["model"], "passed": ok,
                        "checks": [{"name": n, "status": st, "detail": txt} for n, st, txt in ev["checks"]],
                        "key_figure": {"name": row["case"].key_figure[0], "value_si": ev["key"]},
                        "convergence": {"status": ev["converge"][0], "detail": ev["converge"][1]},
                        "wall_time": row["record"].get("wall_time"),
                        "refined_wall_time": row["fine_record"].get("wall_time") if row["fine_record"] else None,
                        "exit_code": row["record"].get("exit_code")})
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "results.yaml"), "w") as f:
        yaml.safe_dump({"subset": a.subset, "models": models, "suite_wall_time": round(total, 1), "rows": summary},
                       f, sort_keys=False)
    if a.docs:
        hard_cases.write_docs(a.docs, rows, total, a.subset, models, a.jobs)
    print("hard cases: %d case run(s) passed, %d failed; suite wall time %.0f s" % (len(rows) - failed, failed, total))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

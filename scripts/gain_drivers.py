#!/usr/bin/env python3
"""What drives the per-trial gain of the calibrated push (issue 71, item 3).

Reads the per-flight force_scale fits of sessions (their session.json, first round) and each
flight's meta.json (dw-import writes each vehicle's median battery voltage, battery_v), and fits
    gain = a + b * (the sufferer's battery voltage) + c * [two neighbours]
by least squares; prints the correlations, the coefficients and the leave-one-flight-out RMS of
the gain predicted with the covariates against the mean alone.

    scripts/gain_drivers.py --sessions session_proof/session_*/untouched/session.json --flights flights
"""
import argparse
import json
import statistics
import sys


def rows_of(sessions, flights):
    rows = []
    for path in sessions:
        with open(path) as f:
            session = json.load(f)
        for c in session["rig_candidates"]:
            if c["effect"] != "force_scale" or c["round"] != 1:
                continue
            for pf in c["per_flight"]:
                if pf["se"] is None:
                    continue
                with open(f"{flights}/{pf['flight']}/meta.json") as f:
                    meta = json.load(f)
                if "battery_v" not in meta:
                    sys.exit(f"{flights}/{pf['flight']}/meta.json: no battery_v (import it again with dw-import)")
                rows.append((pf["flight"], pf["value"], meta["battery_v"][meta["sufferer"]], len(meta["neighbours"])))
    return rows


def corr(x, y):
    mx, my = statistics.mean(x), statistics.mean(y)
    sx = sum((a - mx) ** 2 for a in x) ** 0.5
    sy = sum((b - my) ** 2 for b in y) ** 0.5
    return sum((a - mx) * (b - my) for a, b in zip(x, y)) / (sx * sy)


def fit(rows):
    """Least squares of gain on (1, battery, two neighbours), by the normal equations."""
    X = [(1.0, r[2], 1.0 if r[3] >= 2 else 0.0) for r in rows]
    y = [r[1] for r in rows]
    M = [[sum(x[i] * x[j] for x in X) for j in range(3)] + [sum(x[i] * v for x, v in zip(X, y))] for i in range(3)]
    for i in range(3):
        p = max(range(i, 3), key=lambda r: abs(M[r][i]))
        M[i], M[p] = M[p], M[i]
        for r in range(3):
            if r != i:
                f = M[r][i] / M[i][i]
                M[r] = [a - f * b for a, b in zip(M[r], M[i])]
    return [M[i][3] / M[i][i] for i in range(3)]


def predict(c, r):
    return c[0] + c[1] * r[2] + c[2] * (1.0 if r[3] >= 2 else 0.0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sessions", nargs="+", required=True, help="session.json files")
    ap.add_argument("--flights", required=True, help="the folder of the flight folders")
    a = ap.parse_args()
    rows = rows_of(a.sessions, a.flights)
    if len(rows) < 5:
        sys.exit(f"--sessions: {len(rows)} flights with a force_scale fit; at least 5 are needed")
    for n in sorted({r[3] for r in rows}):
        part = [r for r in rows if r[3] == n]
        if len(part) > 2:
            print(f"{n} neighbour(s): {len(part)} flights, corr(gain, sufferer's battery) "
                  f"{corr([r[1] for r in part], [r[2] for r in part]):.2f}")
    c = fit(rows)
    print(f"gain = {c[0]:.3f} + {c[1]:.3f} V_battery + {c[2]:.3f} [two neighbours]  ({len(rows)} flights)")
    loo, mean_only = [], []
    for i, r in enumerate(rows):
        rest = rows[:i] + rows[i + 1:]
        loo.append(r[1] - predict(fit(rest), r))
        mean_only.append(r[1] - statistics.mean(x[1] for x in rest))
    rms = lambda v: (sum(x * x for x in v) / len(v)) ** 0.5
    print(f"leave one flight out, RMS of the gain: {rms(loo):.3f} with the covariates, {rms(mean_only):.3f} the mean alone")


if __name__ == "__main__":
    main()

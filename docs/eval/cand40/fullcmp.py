"""Two runs of the whole benchmark, step by step: per group of cases and method, successes,
collisions and the mean RMSE e_x / e_y / e_theta, old | new (standard library only).

    python3 docs/eval/cand40/fullcmp.py OLD_DIR NEW_DIR STEP...   (STEP: paper, crowds, ...)
"""
import csv
import os
import sys

RMSE = ('rmse_ex_m', 'rmse_ey_m', 'rmse_etheta_rad')


def summary(rows):
    """'successes/trials coll collisions e_x e_y e_theta' (means over every trial)."""
    n = max(1, len(rows))
    successes = sum(r['success'] == '1' for r in rows)
    collisions = sum(r['failure'].startswith('collision') for r in rows)
    means = ' '.join('%.3f' % (sum(float(r[k]) for r in rows) / n) for k in RMSE)
    return '%d/%d coll %d %s' % (successes, len(rows), collisions, means)


def group_of(step, row):
    """The paper step's six scenarios form one group; elsewhere a case's family (crowd-5 ->
    crowd)."""
    if step == 'paper' and row['case'] != 'random':
        return 'scenarios'
    return row['case'].split('-')[0]


def main(old, new, steps):
    for step in steps:
        runs = [list(csv.DictReader(open(os.path.join(d, step, 'trials.csv')))) for d in (old, new)]
        keys = list(dict.fromkeys((group_of(step, r), r['method']) for r in runs[0] + runs[1]))
        for group, method in keys:
            sides = [summary([r for r in rows if r['method'] == method and
                              group_of(step, r) == group]) for rows in runs]
            print('%-12s %-12s | %s | %s' % (group, method, sides[0], sides[1]))


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2], sys.argv[3:])

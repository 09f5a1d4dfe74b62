"""The default against use_gyro + prediction_turn_time_constant_s 0.5 over seeds 1-100, objective
rows only (from the repository's root: python3 docs/eval/cand40/comb.py)."""
import csv

from fullcmp import RMSE, summary

EVAL = 'docs/eval/'
RUNS = {  # seeds 1-50 from earlier sessions' rows, 51-100 from this one's
    'random': {'default': ['full25/paper', 'cand40/def_random'],
               'cand': ['gyro39/rgt05', 'cand40/cand_random']},
    'turns-30x1': {'default': ['turns30x1', 'cand40/def_turns-30x1'],
                   'cand': ['gyro39/tgt05', 'cand40/cand_turns-30x1']},
}


def load(dirs, case):
    out = {}
    for d in dirs:
        for r in csv.DictReader(open(EVAL + d + '/trials.csv')):
            if r['method'] == 'objective' and r['case'] == case:
                out[int(r['seed'])] = r
    return out


for case, runs in RUNS.items():
    a, b = load(runs['default'], case), load(runs['cand'], case)
    seeds = sorted(set(a) & set(b))
    for name, rows in (('default', a), ('cand', b)):
        print(case, name, summary([rows[s] for s in seeds]))
    both = [s for s in seeds if a[s]['success'] == '1' and b[s]['success'] == '1']
    means = ' '.join('%.3f/%.3f' % tuple(sum(float(x[s][k]) for s in both) / len(both)
                                        for x in (a, b)) for k in RMSE)
    lower = [sum(float(b[s][k]) < float(a[s][k]) for s in both) for k in RMSE]
    print(' both', len(both), means, 'cand lower in', lower)

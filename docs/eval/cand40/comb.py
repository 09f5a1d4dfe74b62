# The default against use_gyro + prediction_turn_time_constant_s 0.5 over seeds 1-100 (run from
# the repository's root: python3 docs/eval/cand40/comb.py). Objective rows only.
import csv,sys,math
def load(fs,case):
    out={}
    for f in fs:
        for r in csv.DictReader(open(f)):
            if r['method']=='objective' and r['case']==case: out[int(r['seed'])]=r
    return out
T='docs/eval/'
C=T+'cand40/'
sets={'random':{'default':[T+'full25/paper/trials.csv',C+'def_random/trials.csv'],'cand':[T+'gyro39/rgt05/trials.csv',C+'cand_random/trials.csv']},
      'turns-30x1':{'default':[T+'turns30x1/trials.csv',C+'def_turns-30x1/trials.csv'],'cand':[T+'gyro39/tgt05/trials.csv',C+'cand_turns-30x1/trials.csv']}}
k3=['rmse_ex_m','rmse_ey_m','rmse_etheta_rad']
for case,d in sets.items():
    A=load(d['default'],case); B=load(d['cand'],case)
    keys=sorted(set(A)&set(B))
    for name,X in (('default',A),('cand',B)):
        rows=[X[k] for k in keys]
        sr=sum(r['success']=='1' for r in rows)
        col=sum(r['failure'].startswith('collision') for r in rows)
        m=[sum(float(r[x]) for r in rows)/len(rows) for x in k3]
        print(case,name,len(rows),'SR',sr,'coll',col,' '.join('%.3f'%v for v in m))
    both=[k for k in keys if A[k]['success']=='1' and B[k]['success']=='1']
    print(' both',len(both),' '.join('%.3f/%.3f'%(sum(float(A[k][x]) for k in both)/len(both),sum(float(B[k][x]) for k in both)/len(both)) for x in k3),
          'B lower',[sum(float(B[k][x])<float(A[k][x]) for k in both) for x in k3])

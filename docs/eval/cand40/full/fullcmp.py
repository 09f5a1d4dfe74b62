# fullcmp.py OLD_DIR NEW_DIR STEP...: per step and method, SR and collisions and RMSE means, old vs new.
import csv,sys,os,collections
old,new=sys.argv[1],sys.argv[2]
k3=['rmse_ex_m','rmse_ey_m','rmse_etheta_rad']
for step in sys.argv[3:]:
    A=list(csv.DictReader(open(os.path.join(old,step,'trials.csv'))))
    B=list(csv.DictReader(open(os.path.join(new,step,'trials.csv'))))
    groups=collections.OrderedDict()
    for r in A+B: groups.setdefault((r['case'].split('-')[0] if step!='paper' or r['case']=='random' else 'scenarios',r['method']),None)
    for g,m in groups:
        def sel(R): return [r for r in R if r['method']==m and ((r['case'].split('-')[0] if step!='paper' or r['case']=='random' else 'scenarios')==g)]
        a,b=sel(A),sel(B)
        def s(R):
            sr=sum(r['success']=='1' for r in R); col=sum(r['failure'].startswith('collision') for r in R)
            mm=' '.join('%.3f'%(sum(float(r[x]) for r in R)/max(1,len(R))) for x in k3)
            return '%d/%d coll %d %s'%(sr,len(R),col,mm)
        print('%-12s %-12s | %s | %s'%(g,m,s(a),s(b)))

# Mean height (mm), bed top (mm) and kinetic energy at step 20 000 (mJ) of each run of seeds.sh,
# and the mean and standard deviation of the height per deck and engine.
import glob, os, sys, statistics as st
OUT = os.environ.get('OUT', '/tmp/seeds')
def points(f):
    t=open(f).read().split()
    i=t.index('POINTS'); n=int(t[i+1]); v=list(map(float,t[i+3:i+3+3*n]))
    return [v[3*k:3*k+3] for k in range(n)]
def ke(log, step):
    for l in open(log):
        w=l.split()
        if len(w)>3 and w[0]==str(step):
            try: return float(w[2])
            except: pass
    return float('nan')
res={}
for d in sorted(glob.glob(OUT + '/in.*_*_*')):
    deck,seed,eng=os.path.basename(d).rsplit('_',2)
    pref='newModels' if 'newModels' in deck else 'cohesion'
    f=f'{d}/post/{pref}_49600.vtk'
    if not os.path.exists(f): continue
    p=points(f); z=[q[2] for q in p]
    res.setdefault((deck,eng),[]).append((seed,len(p),1000*st.mean(z),1000*max(z),1000*ke(d+'/log.txt',20000)))
for k,v in sorted(res.items()):
    print(k)
    for r in v: print('   ',r)
    h=[r[2] for r in v]
    if len(h)>1: print('   mean height %.3f mm, sd %.3f, n %d'%(st.mean(h),st.stdev(h),len(h)))

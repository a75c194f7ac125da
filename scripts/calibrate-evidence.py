"""Error rate of each evidence test from scripts/calibrate-evidence.sh's runs."""
import json,glob,collections,sys
OUT=sys.argv[1] if len(sys.argv)>1 else '/tmp/calibrate-evidence'
rule_of={'seen-space':['real-refuted','mirror-refuted'],'seen-surface':['seen-surface'],'image-support':['support'],
 'frame-free-space':['frame-free-space'],'depth':['depth'],'echo-strength':['echo-strength'],'echo-order':['dual-return'],
 'level-surface':['level-surface'],'seen-through':['seen-through']}
for t,rules in rule_of.items():
    fr=collections.Counter(); fo=collections.Counter(); fams=collections.defaultdict(lambda:[0,0,0,0])
    for m in glob.glob(f'{OUT}/o-{t}-*/metrics.json'):
        fam=m.split('/')[-2][len('o-'+t)+1:]
        d=json.load(open(m))['rules']
        for k,v in d.items():
            r,pred=k.split('/')
            if r not in rules: continue
            R=v[5]; real=v[6]+v[1]
            if pred=='reflection': fr['R']+=R; fr['real']+=real; fams[fam][0]+=R; fams[fam][1]+=real
            elif pred in('obstacle','normal'): fo['R']+=R; fo['real']+=real; fams[fam][2]+=R; fams[fam][3]+=real
    def e(c,wrong): n=c['R']+c['real']; return (c[wrong]/n if n else float('nan'), n)
    er=e(fr,'real'); eo=e(fo,'R')
    print(f"{t:18s} favours R: err {er[0]:.3f} n={er[1]:8d}   favours real: err {eo[0]:.3f} n={eo[1]:8d}")
    for fam,(a,b,c,dd) in sorted(fams.items()):
        print(f"     {fam:20s} R: {b/(a+b) if a+b else float('nan'):.2f} ({a+b:7d})  real: {c/(c+dd) if c+dd else float('nan'):.2f} ({c+dd:7d})")

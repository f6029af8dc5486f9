import json,subprocess,sys,random,time
exe=sys.argv[1]
def scene(n,th,gap_um,ra,rb,B=0.1):
    x=5.0+gap_um*1e-3/2
    return f"""magbake: 1
name: two_balls
units: {{length: mm, angle: deg}}
time: {{fps: 30, frames: [1, 2], dt: 0.001}}
gravity: [0, 0, 0]
magnetics: {{quality: high, induction: coupled, external_field: [{B}, 0, 0], theta: {th}, soft_cells_across: {n}}}
materials:
  steel: {{kind: soft, chi: 700, density: 7850}}
bodies:
  - {{name: a, shape: {{sphere: {{radius: 5}}}}, material: steel, position: [{-x}, 0, 0], orientation: {{axis: {ra[0]}, angle: {ra[1]}}}}}
  - {{name: b, shape: {{sphere: {{radius: 5}}}}, material: steel, position: [{x}, 0, 0], orientation: {{axis: {rb[0]}, angle: {rb[1]}}}}}
"""
random.seed(int(sys.argv[3]) if len(sys.argv)>3 else 1)
def rturn():
    v=[random.uniform(-1,1) for _ in range(3)]; return (v, random.uniform(-180,180))
cases=eval(sys.argv[2])
for (n,th,gap,turn) in cases:
    ra,rb=(([0,0,1],0),([0,0,1],0)) if not turn else (rturn(),rturn())
    open('/tmp/s17/t.yaml','w').write(scene(n,th,gap,ra,rb))
    t0=time.time()
    out=subprocess.run([exe,'eval','/tmp/s17/t.yaml','--json'],capture_output=True,text=True)
    try:
        d=json.loads(out.stdout); f=d['bodies'][0]['force']; ind=d.get('induction',{})
        print(f"n {n:3d} th {th} gap {gap:6.1f}um turn {turn} Fx {f[0]:9.3f} |Fyz| {abs(f[1])+abs(f[2]):.3f} it {ind.get('iterations')} res {ind.get('residual'):.1e} {time.time()-t0:.1f}s",flush=True)
    except Exception as e:
        print(n,th,gap,'ERR',out.stderr[-300:])

import subprocess, json, sys, math
mag = sys.argv[1]; r=float(sys.argv[2]); extra = sys.argv[3] if len(sys.argv)>3 else ""
shape = "{box: [10, 10, 10]}" if mag=="cube" else "{cylinder: {radius: 5, height: 10}}"
def ev(pos):
    y=f"""magbake: 1
units: {{length: mm, angle: deg}}
{extra}
materials: {{N42: {{kind: permanent, remanence: 1.3, density: 7500}}, steel: {{kind: soft, chi: 700, density: 7850}}}}
bodies:
  - {{name: mag, shape: {shape}, material: N42, magnetization: [0, 0, 1], position: [0,0,5]}}
  - {{name: ball, shape: {{sphere: {{radius: {r}}}}}, material: steel, position: [{pos[0]}, {pos[1]}, {pos[2]}]}}
"""
    open('loop.yaml','w').write(y)
    out=json.loads(subprocess.run(['/work/main/build/bake/magbake','eval','loop.yaml','--json'],capture_output=True,text=True).stdout)
    b=[x for x in out['bodies'] if x['name']=='ball'][0]
    return b['force'], out.get('energy', out.get('magnetic_energy'))
# closed loop around the rim (y = 5, z = 10 for the cube's edge or the cylinder's rim): inner arc at
# r + 0.3 mm, outer arc at r + 1.5 mm, from -60 to 150 degrees (0 = along +y, 90 = along +z)
n=int(sys.argv[4]) if len(sys.argv)>4 else 40
W=0; E=[]
def arc(rad, a0, a1, m):
    return [(0.0, 5 + rad*math.cos(math.radians(a0 + (a1-a0)*k/m)), 10 + rad*math.sin(math.radians(a0 + (a1-a0)*k/m))) for k in range(m+1)]
ri, ro = r + 0.3, r + 1.5
radial = lambda a, r0, r1: [(0.0, 5 + (r0 + (r1-r0)*k/n)*math.cos(math.radians(a)), 10 + (r0 + (r1-r0)*k/n)*math.sin(math.radians(a))) for k in range(1, n)]
pts = arc(ri, 0, 90, n) + radial(90, ri, ro) + arc(ro, 90, 0, n) + radial(0, ro, ri) + [arc(ri, 0, 90, n)[0]]
Fs=[]
for p in pts:
    F,e=ev(p); Fs.append(F); E.append(e)
for k in range(len(pts)-1):
    d=[(pts[k+1][i]-pts[k][i])*1e-3 for i in range(3)]
    Fm=[0.5*(Fs[k][i]+Fs[k+1][i]) for i in range(3)]
    W+=sum(Fm[i]*d[i] for i in range(3))
print("loop work %.4g mJ, energy range %.4g mJ, |F| max %.3f N" % (W*1e3, (max(E)-min(E))*1e3, max(math.sqrt(sum(c*c for c in F)) for F in Fs)))

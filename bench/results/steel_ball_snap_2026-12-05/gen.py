import itertools
cases=[]
for r in (2,4,6):
  for (name,pos) in (("side",(0,5+r+3,r)),("edge",(0,5+r+1,10+r+1)),("top",(1.5,1,10+r+2))):
    for mag in ("cube","cyl"):
      cases.append((r,name,pos,mag))
for (r,name,pos,mag) in cases:
  nm=f"s_{mag}_{name}_r{r}"
  shape = "{box: [10, 10, 10]}" if mag=="cube" else "{cylinder: {radius: 5, height: 10}}"
  z = pos[2]
  open(nm+".yaml","w").write(f"""magbake: 1
name: {nm}
units: {{length: mm, angle: deg}}
time: {{fps: 100, frames: [1, 51], dt: 0.001}}
gravity: [0, 0, -9810]
materials:
  N42: {{kind: permanent, remanence: 1.3, density: 7500}}
  wood: {{kind: none, density: 700}}
  steel: {{kind: soft, chi: 700, density: 7850}}
bodies:
  - {{name: table, shape: {{box: [200, 200, 10]}}, material: wood, motion: static, position: [0, 0, -5]}}
  - {{name: mag, shape: {shape}, material: N42, magnetization: [0, 0, 1], position: [0, 0, 5], friction: 0.5}}
  - {{name: ball, shape: {{sphere: {{radius: {r}}}}}, material: steel, position: [{pos[0]}, {pos[1]}, {z}], friction: 0.5}}
outputs:
  cache: {nm}.h5
""")
  print(nm)

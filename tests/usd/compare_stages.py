#!/usr/bin/env python3
"""Two USD stages hold the same scene (usd-core): layer metadata, prims (type, kind, customData),
every attribute (type, variability, custom, interpolation, time samples and every value, exactly)
and relationship targets. Used to check magbake's .usdc writer against its .usda writer.

Usage: compare_stages.py A.usda B.usdc
"""
import sys
from pxr import Usd, Sdf
a = Usd.Stage.Open(sys.argv[1]); b = Usd.Stage.Open(sys.argv[2])
la, lb = a.GetRootLayer(), b.GetRootLayer()
print("layer metadata equal:", all(la.pseudoRoot.GetInfo(k) == lb.pseudoRoot.GetInfo(k) for k in la.pseudoRoot.ListInfoKeys()), sorted(la.pseudoRoot.ListInfoKeys()) == sorted(lb.pseudoRoot.ListInfoKeys()))
n = diffs = 0
pa = [p.GetPath() for p in a.Traverse()]; pb = [p.GetPath() for p in b.Traverse()]
print("prims", len(pa), len(pb), pa == pb)
for path in pa:
    x, y = a.GetPrimAtPath(path), b.GetPrimAtPath(path)
    if x.GetTypeName() != y.GetTypeName() or x.GetMetadata("kind") != y.GetMetadata("kind") or x.GetCustomData() != y.GetCustomData(): diffs += 1; print("prim diff", path)
    for at in x.GetAttributes():
        bt = y.GetAttribute(at.GetName())
        if not bt or at.GetTypeName() != bt.GetTypeName() or at.GetVariability() != bt.GetVariability() or at.IsCustom() != bt.IsCustom() or at.GetMetadata("interpolation") != bt.GetMetadata("interpolation"):
            diffs += 1; print("attr meta diff", at.GetPath()); continue
        ts = at.GetTimeSamples()
        if ts != bt.GetTimeSamples(): diffs += 1; print("times diff", at.GetPath()); continue
        for t in (ts or [Usd.TimeCode.Default()]):
            n += 1
            va, vb = at.Get(t), bt.Get(t)
            if va != vb: diffs += 1; print("value diff", at.GetPath(), t, str(va)[:80], str(vb)[:80])
    for r in x.GetRelationships():
        if r.GetTargets() != y.GetRelationship(r.GetName()).GetTargets(): diffs += 1; print("rel diff", r.GetPath())
print(f"{n} values compared, {diffs} differences")
assert pa == pb and n > 0 and diffs == 0
assert sorted(la.pseudoRoot.ListInfoKeys()) == sorted(lb.pseudoRoot.ListInfoKeys())
assert all(la.pseudoRoot.GetInfo(k) == lb.pseudoRoot.GetInfo(k) for k in la.pseudoRoot.ListInfoKeys())

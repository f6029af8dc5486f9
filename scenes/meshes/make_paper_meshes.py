#!/usr/bin/env python3
"""Generates the meshes of the paper scenes in this folder (run from anywhere; writes next to itself).

Needs numpy (e.g. Debian's python3-numpy: run it with /usr/bin/python3). Units: millimetres, Z up.
The output is deterministic. Every mesh is checked as it is written (the OBJ text is parsed back)
before the file is replaced: closed and 2-manifold (every directed edge once, its reverse once, one
fan of triangles around every vertex), one connected piece, outward orientation (positive signed
volume), no degenerate triangles, welded vertices (no two at the same position, also in single
precision, which is what the importer reads), no self-intersections (edge against triangle tests of
nearby triangles). Any violation stops the script with a non-zero exit status.

bowl.obj: a static bowl that holds steel balls, a thick-walled spherical cap, open at the top.
  Inside: a sphere cap of radius BOWL_R_IN = 40 centred on the z axis at z = 40, so the INSIDE
  BOTTOM IS AT z = 0 (on the axis). The wall is BOWL_WALL = 4 thick everywhere (the outside is the
  concentric sphere of radius 44). The rim is a flat annulus at z = BOWL_RIM_Z = 25 joining the
  inner wall (RIM INNER RADIUS sqrt(40^2 - 15^2) = 37.081) to the outer wall (rim outer radius
  sqrt(44^2 - 15^2) = 41.364). Under the bottom a flat foot disc of radius BOWL_FOOT_R = 12 fills
  the gap between the outer sphere and the plane z = -4, so the OUTER BOTTOM IS FLAT AT z = -4 and
  the bowl sits on a ground plane there (the foot's side is a 1.67 mm high cylinder). The inside
  is 25 deep; a ball of radius r resting at the bottom has its centre at z = r on the axis.
  A surface of revolution with BOWL_SEGMENTS = 48 segments around; the profile has 18 segments on
  the inner sphere, 16 on the outer one, 1 across the rim and 4 on the foot.

digit_2.obj, digit_0.obj, digit_8.obj: the soft-iron characters of the "2008" scene (Fig. 8),
  solid extrusions of a 2D outline: DIGIT_HEIGHT = 24 tall (y), DIGIT_WIDTH = 16 wide (x),
  DIGIT_THICKNESS = 6 thick (z, from -3 to 3), readable from +z with x to the right and y up,
  bounding box centred at the origin. Strokes are DIGIT_STROKE = 4 wide with round ends: the
  outline is the zero level of the distance to the stroke centre lines minus 2, traced by marching
  squares on a DIGIT_GRID = 0.05 mm grid and simplified to DIGIT_TOLERANCE = 0.03 mm (so every
  curve has dozens of points; corners the tracing cut off are restored); the caps are ear-clipped
  with the holes bridged. "0": an oval ring (centre line an ellipse of semi-axes 6 x 10), one hole.
  "8": two stacked rings (lower centre line an ellipse 6 x 5.25 around y = -4.75, upper 5 x 4.75
  around y = 5.25, touching at the waist), two holes. "2": a hook (200 degrees of a centre-line
  circle of radius 6 around (0, 4), from its round end at the upper left clockwise over the top),
  a diagonal leaving the circle tangentially down to the bottom left, and a flat base bar 16 x 4
  with square ends (y from -12 to -8).

dragon.obj: the "simple dragon model" of Fig. 9, an organic closed genus-0 solid: a smooth union
  (polynomial smooth-min) of signed-distance primitives: a body and chest, haunches, four legs
  with flat feet standing on z = 0, a neck curving up to a head with a snout and two horns, a long
  tail tapering and curling to one side, and two wings on the back, each a main lobe and a trailing
  lobe, flattened ellipsoids 5.5-6 mm thick. Polygonized by marching tetrahedra (six tetrahedra per
  cube) on a DRAGON_GRID = 2 mm grid with vertices welded by grid edge (grid values within 0.1 of
  the spacing of zero are pushed off it, which keeps vertices away from grid nodes), then
  decimated by quadric-error edge collapses that keep it a closed 2-manifold to DRAGON_TRIANGLES =
  7000 triangles, then scaled by 0.914 to DRAGON_LENGTH = 100. Head towards +x, bounding box
  centred at x = y = 0, lowest point z = 0 (the flat soles of the four feet). Size 100 x 39.6 x
  58.3 mm (x, y, z), volume about 63,000 mm^3 (63 cm^3): an animal shape fills only a fraction of
  its bounding box; scale it in the scene for more.
"""
import heapq
import itertools
import math
import os
import sys

try:
    import numpy as np
except ImportError:  # pragma: no cover
    sys.exit("make_paper_meshes.py needs numpy (e.g. apt install python3-numpy; run /usr/bin/python3 make_paper_meshes.py)")

HERE = os.path.dirname(os.path.abspath(__file__))

# Bowl.
BOWL_R_IN, BOWL_WALL, BOWL_RIM_Z, BOWL_FOOT_R = 40.0, 4.0, 25.0, 12.0
BOWL_SEGMENTS, BOWL_N_INNER, BOWL_N_OUTER, BOWL_N_FOOT = 48, 18, 16, 3

# Digits.
DIGIT_HEIGHT, DIGIT_WIDTH, DIGIT_THICKNESS, DIGIT_STROKE = 24.0, 16.0, 6.0, 4.0
DIGIT_GRID, DIGIT_TOLERANCE = 0.05, 0.03

# Dragon.
DRAGON_LENGTH, DRAGON_GRID, DRAGON_TRIANGLES = 100.0, 2.0, 7000

MAX_TRIANGLES = {"bowl": 4000, "digit_2": 3000, "digit_0": 3000, "digit_8": 3000, "dragon": 8000}
MIN_TRIANGLES = {"dragon": 3000}
DEGENERATE_AREA = 1e-6  # mm^2


# ----------------------------------------------------------------------------------------------
# Bowl: a surface of revolution.

def bowl():
    c = BOWL_R_IN  # sphere centre height (inside bottom at z = 0)
    r_out = BOWL_R_IN + BOWL_WALL
    h = c - BOWL_RIM_Z
    prof = []  # (r, z), counter-clockwise around the cross-section, axis to axis
    for i in range(BOWL_N_FOOT + 1):  # foot disc underneath, z = -wall
        prof.append((BOWL_FOOT_R * i / BOWL_N_FOOT, -BOWL_WALL))
    phi0, phi1 = math.asin(BOWL_FOOT_R / r_out), math.acos(h / r_out)
    for i in range(BOWL_N_OUTER + 1):  # outer sphere from the foot's edge up to the rim
        p = phi0 + (phi1 - phi0) * i / BOWL_N_OUTER
        prof.append((r_out * math.sin(p), c - r_out * math.cos(p)))
    th1 = math.acos(h / BOWL_R_IN)
    for i in range(BOWL_N_INNER + 1):  # across the rim, then down the inner sphere
        t = th1 * (1 - i / BOWL_N_INNER)
        prof.append((BOWL_R_IN * math.sin(t), c - BOWL_R_IN * math.cos(t)))
    prof[-1] = (0.0, 0.0)
    n = BOWL_SEGMENTS
    verts, ring = [], []
    for r, z in prof:
        if r == 0.0:
            ring.append([len(verts)] * n)
            verts.append((0.0, 0.0, z))
        else:
            ring.append(list(range(len(verts), len(verts) + n)))
            verts += [(r * math.cos(2 * math.pi * j / n), r * math.sin(2 * math.pi * j / n), z) for j in range(n)]
    tris = []
    for k in range(len(prof) - 1):
        for j in range(n):
            a, b = ring[k][j], ring[k + 1][j]
            c_, d = ring[k + 1][(j + 1) % n], ring[k][(j + 1) % n]
            # the profile runs counter-clockwise in (r, z): (a, d, c) faces outward
            for t in ((a, d, c_), (a, c_, b)):
                if len(set(t)) == 3:
                    tris.append(t)
    return np.array(verts), np.array(tris)


# ----------------------------------------------------------------------------------------------
# Digits: 2D stroke outlines, traced, simplified, triangulated, extruded.

def seg_distance(px, py, segs):
    """Distance from points to a union of segments [(x0, y0, x1, y1), ...]."""
    d = np.full(px.shape, np.inf)
    for x0, y0, x1, y1 in segs:
        dx, dy = x1 - x0, y1 - y0
        t = np.clip(((px - x0) * dx + (py - y0) * dy) / (dx * dx + dy * dy), 0.0, 1.0)
        d = np.minimum(d, np.hypot(px - x0 - t * dx, py - y0 - t * dy))
    return d


def polyline(points):
    return [(points[i][0], points[i][1], points[i + 1][0], points[i + 1][1]) for i in range(len(points) - 1)]


def ellipse(cx, cy, a, b, n=720):
    return polyline([(cx + a * math.cos(2 * math.pi * i / n), cy + b * math.sin(2 * math.pi * i / n)) for i in range(n + 1)])


def arc(cx, cy, r, a0, a1, n=360):
    return [(cx + r * math.cos(a0 + (a1 - a0) * i / n), cy + r * math.sin(a0 + (a1 - a0) * i / n)) for i in range(n + 1)]


def digit_field(ch, px, py):
    """Signed field (< 0 inside) of a character in a 16 x 24 box centred at the origin."""
    w2 = DIGIT_STROKE / 2
    if ch == "0":
        return seg_distance(px, py, ellipse(0, 0, 8 - w2, 12 - w2)) - w2
    if ch == "8":
        return np.minimum(seg_distance(px, py, ellipse(0, -4.75, 8 - w2, 5.25)),
                          seg_distance(px, py, ellipse(0, 5.25, 7 - w2, 4.75))) - w2
    if ch == "2":
        cx, cy, r = 0.0, 4.0, 8 - w2     # hook: centre-line circle, outer radius 8 reaches y = 12
        ex, ey = -8 + w2 + 0.5, -12 + w2  # diagonal ends above the base bar's left end
        # tangent point of the line from (ex, ey) to the circle, on its right-hand side
        dx, dy = cx - ex, cy - ey
        dist = math.hypot(dx, dy)
        base = math.atan2(-dy, -dx)       # direction centre -> end point
        t_ang = base + math.acos(r / dist)
        hook = arc(cx, cy, r, math.radians(155), t_ang - 2 * math.pi if t_ang > math.radians(155) else t_ang)
        stroke = polyline(hook) + [(hook[-1][0], hook[-1][1], ex, ey)]
        f = seg_distance(px, py, stroke) - w2
        bar = np.maximum(np.abs(px) - 8, np.abs(py + 12 - w2) - w2)  # base bar 16 x 4, square ends
        return np.minimum(f, bar)
    raise ValueError(ch)


def marching_squares(f, xs, ys):
    """Closed contours of f = 0 (inside f < 0), each with the inside on its left: outer outlines
    counter-clockwise, holes clockwise. f[i, j] is the value at (xs[i], ys[j])."""
    inside = f < 0
    if inside[0, :].any() or inside[-1, :].any() or inside[:, 0].any() or inside[:, -1].any():
        raise RuntimeError("shape touches the grid border")
    corners = ((0, 0), (1, 0), (1, 1), (0, 1))  # counter-clockwise
    c = [inside[di:inside.shape[0] - 1 + di, dj:inside.shape[1] - 1 + dj] for di, dj in corners]
    mixed = ~((c[0] == c[1]) & (c[1] == c[2]) & (c[2] == c[3]))
    nxt, pos = {}, {}
    for i, j in np.argwhere(mixed):
        nodes = [(i + di, j + dj) for di, dj in corners]
        crossings = []  # (edge key, inside -> outside?) in counter-clockwise order
        for k in range(4):
            a, b = nodes[k], nodes[(k + 1) % 4]
            if inside[a] != inside[b]:
                key = (a, b) if a < b else (b, a)
                if key not in pos:
                    t = f[a] / (f[a] - f[b])
                    pos[key] = (xs[a[0]] + t * (xs[b[0]] - xs[a[0]]), ys[a[1]] + t * (ys[b[1]] - ys[a[1]]))
                crossings.append((key, bool(inside[a])))
        m = len(crossings)
        centre_inside = sum(f[nd] for nd in nodes) < 0
        for k, (key, leaving) in enumerate(crossings):
            if leaving:  # inside -> outside: the segment runs to the neighbouring crossing
                step = 1 if (m == 2 or centre_inside) else -1
                nxt[key] = crossings[(k + step) % m][0]
    loops, seen = [], set()
    for start in nxt:
        if start in seen:
            continue
        loop, key = [], start
        while key not in seen:
            seen.add(key)
            loop.append(pos[key])
            key = nxt[key]
        if key != start:
            raise RuntimeError("marching squares: contour does not close")
        loops.append(np.array(loop))
    return loops


def simplify_closed(pts, tol):
    """Douglas-Peucker on a closed polyline (keeps sharp corners, drops collinear points)."""
    n = len(pts)
    i0 = int(np.argmax(np.linalg.norm(pts - pts.mean(0), axis=1)))
    pts = np.roll(pts, -i0, axis=0)
    i1 = int(np.argmax(np.linalg.norm(pts - pts[0], axis=1)))
    keep = np.zeros(n + 1, bool)
    ext = np.vstack([pts, pts[:1]])
    stack = [(0, i1), (i1, n)]
    keep[[0, i1, n]] = True
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        seg = ext[b] - ext[a]
        rel = ext[a + 1:b] - ext[a]
        ln = np.hypot(*seg)
        d = np.abs(seg[0] * rel[:, 1] - seg[1] * rel[:, 0]) / ln if ln > 0 else np.hypot(rel[:, 0], rel[:, 1])
        k = int(np.argmax(d))
        if d[k] > tol:
            m = a + 1 + k
            keep[m] = True
            stack += [(a, m), (m, b)]
    return ext[:n][keep[:n]]


def sharpen_corners(pts, min_len):
    """Marching squares cuts sharp corners off (a short segment between two kept points where
    the outline turns by more than 25 degrees): such a pair becomes the intersection of the lines
    through its neighbouring segments."""
    pts = [np.array(p) for p in pts]
    changed = True
    while changed:
        changed = False
        n = len(pts)
        for i in range(n):
            a, b = pts[i], pts[(i + 1) % n]
            if np.hypot(*(b - a)) >= min_len:
                continue
            pa, nb = pts[i - 1], pts[(i + 2) % n]
            d1, d2 = a - pa, nb - b
            den = d1[0] * d2[1] - d1[1] * d2[0]
            if abs(den) < math.sin(math.radians(25)) * np.hypot(*d1) * np.hypot(*d2) and d1 @ d2 > 0:
                continue  # a smooth curve
            t = ((b - pa)[0] * d2[1] - (b - pa)[1] * d2[0]) / den
            c = pa + t * d1
            if np.hypot(*(c - (a + b) / 2)) > min_len:
                continue
            pts[i] = c
            del pts[(i + 1) % n]
            changed = True
            break
    return np.array(pts)


def signed_area(p):
    return 0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


def cross2(o, a, b):
    return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0])


def segments_cross(P, loops):
    """Number of pairs of non-adjacent outline segments that touch or cross."""
    segs = []
    for lp in loops:
        for k in range(len(lp)):
            segs.append((lp[k], lp[(k + 1) % len(lp)]))
    s = np.array(segs)
    a, b = P[s[:, 0]], P[s[:, 1]]
    n = len(s)
    i, j = np.triu_indices(n, 1)
    share = (s[i, 0] == s[j, 0]) | (s[i, 0] == s[j, 1]) | (s[i, 1] == s[j, 0]) | (s[i, 1] == s[j, 1])
    i, j = i[~share], j[~share]
    d1, d2 = cross2(a[i], b[i], a[j]), cross2(a[i], b[i], b[j])
    d3, d4 = cross2(a[j], b[j], a[i]), cross2(a[j], b[j], b[i])
    return int(np.sum((d1 * d2 <= 0) & (d3 * d4 <= 0)))


def bridge_holes(P, outer, holes):
    """One weakly simple polygon (vertex indices) from a ccw outline and cw holes."""
    poly = list(outer)
    for hole in sorted(holes, key=lambda h: -max(P[v, 0] for v in h)):
        mi = max(range(len(hole)), key=lambda k: (P[hole[k], 0], -k))
        M = P[hole[mi]]
        best = None  # (x of the ray hit, polygon slot of the visible vertex)
        for s in range(len(poly)):
            a, b = P[poly[s]], P[poly[(s + 1) % len(poly)]]
            if (a[1] - M[1]) * (b[1] - M[1]) > 0 or a[1] == b[1]:
                continue
            x = a[0] + (M[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
            if x <= M[0] or (best is not None and x >= best[0]):
                continue
            # the solid is on the left of every edge, so the edges the ray can reach go upward
            if b[1] < a[1]:
                continue
            slot = s if a[0] > b[0] else (s + 1) % len(poly)
            best = (x, slot)
        if best is None:
            raise RuntimeError("hole bridging: no visible outline edge")
        x, slot = best
        I = np.array([x, M[1]])
        cand = P[poly[slot]]
        # a reflex vertex inside the triangle (M, I, cand) hides cand: take the one at the smallest angle
        tri = np.array([M, I, cand])
        if cross2(tri[0], tri[1], tri[2]) < 0:
            tri = tri[[0, 2, 1]]
        best_ang = None
        for s in range(len(poly)):
            v = P[poly[s]]
            if s == slot:
                continue
            pv, nv = P[poly[s - 1]], P[poly[(s + 1) % len(poly)]]
            if cross2(pv, v, nv) >= 0:  # convex
                continue
            if min(cross2(tri[0], tri[1], v), cross2(tri[1], tri[2], v), cross2(tri[2], tri[0], v)) < 0:
                continue
            ang = (abs(math.atan2(v[1] - M[1], v[0] - M[0])), float(np.hypot(*(v - M))))
            if best_ang is None or ang < best_ang[0]:
                best_ang = (ang, s)
        if best_ang is not None:
            slot = best_ang[1]
        h = hole[mi:] + hole[:mi]
        poly = poly[:slot + 1] + h + [h[0], poly[slot]] + poly[slot + 1:]
    return poly


def ear_clip(P, poly):
    """Triangulates a weakly simple ccw polygon by ear clipping, best-shaped ear first."""
    n = len(poly)
    idx = np.array(poly)
    prv, nxt = [(s - 1) % n for s in range(n)], [(s + 1) % n for s in range(n)]
    active = np.ones(n, bool)
    quality = np.full(n, -1.0)

    def evaluate(s):
        a, b, c = idx[prv[s]], idx[s], idx[nxt[s]]
        pa, pb, pc = P[a], P[b], P[c]
        area2 = cross2(pa, pb, pc)
        if area2 <= 1e-10:
            return -1.0
        others = idx[active]
        others = others[(others != a) & (others != b) & (others != c)]
        q = P[others]
        eps = -1e-12
        inside = (cross2(pa, pb, q) >= eps) & (cross2(pb, pc, q) >= eps) & (cross2(pc, pa, q) >= eps)
        if inside.any():
            return -1.0
        l2 = np.sum((pa - pb) ** 2) + np.sum((pb - pc) ** 2) + np.sum((pc - pa) ** 2)
        return 2 * math.sqrt(3) * area2 / l2  # 1 for an equilateral triangle

    for s in range(n):
        quality[s] = evaluate(s)
    tris, left = [], n
    while left > 3:
        s = int(np.argmax(np.where(active, quality, -2.0)))
        if quality[s] < 0:
            raise RuntimeError("ear clipping: no ear left")
        tris.append((idx[prv[s]], idx[s], idx[nxt[s]]))
        active[s] = False
        left -= 1
        p, q = prv[s], nxt[s]
        nxt[p], prv[q] = q, p
        quality[p], quality[q] = evaluate(p), evaluate(q)
    s = int(np.argmax(active))
    last = (idx[prv[s]], idx[s], idx[nxt[s]])
    if cross2(P[last[0]], P[last[1]], P[last[2]]) <= 0:
        raise RuntimeError("ear clipping: degenerate last triangle")
    tris.append(last)
    return tris


def digit(ch):
    m = 1.0
    xs = np.arange(-DIGIT_WIDTH / 2 - m, DIGIT_WIDTH / 2 + m + 1e-9, DIGIT_GRID) + 1e-4
    ys = np.arange(-DIGIT_HEIGHT / 2 - m, DIGIT_HEIGHT / 2 + m + 1e-9, DIGIT_GRID) + 1e-4
    px, py = np.meshgrid(xs, ys, indexing="ij")
    f = digit_field(ch, px, py)
    f[np.abs(f) < 1e-9] = 1e-9
    loops = [sharpen_corners(simplify_closed(lp, DIGIT_TOLERANCE), 0.25) for lp in marching_squares(f, xs, ys)]
    loops.sort(key=lambda lp: -abs(signed_area(lp)))
    outers = [lp for lp in loops if signed_area(lp) > 0]
    holes = [lp for lp in loops if signed_area(lp) < 0]
    if len(outers) != 1:
        raise RuntimeError(f"digit {ch}: {len(outers)} outlines")
    P = np.vstack(loops)
    P -= (P.min(0) + P.max(0)) / 2  # bounding box centred
    offs = np.cumsum([0] + [len(lp) for lp in loops])
    loop_idx = [list(range(offs[k], offs[k + 1])) for k in range(len(loops))]
    outer_idx = loop_idx[0]
    hole_idx = loop_idx[1:]
    if segments_cross(P, loop_idx):
        raise RuntimeError(f"digit {ch}: outline touches itself")
    cap = ear_clip(P, bridge_holes(P, outer_idx, hole_idx))
    # the cap must tile the region exactly: every triangle ccw, areas summing to the region's
    areas = cross2(P[[t[0] for t in cap]], P[[t[1] for t in cap]], P[[t[2] for t in cap]]) / 2
    region = sum(signed_area(P[lp]) for lp in loop_idx)
    if areas.min() <= 0 or abs(areas.sum() - region) > 1e-9 * region:
        raise RuntimeError(f"digit {ch}: cap triangulation does not tile the outline")
    n = len(P)
    z = DIGIT_THICKNESS / 2
    verts = np.vstack([np.column_stack([P, np.full(n, z)]), np.column_stack([P, np.full(n, -z)])])
    tris = [(a, b, c) for a, b, c in cap] + [(a + n, c + n, b + n) for a, b, c in cap]
    for lp in loop_idx:  # side walls; the inside is on the left of every outline edge
        for k in range(len(lp)):
            p, q = lp[k], lp[(k + 1) % len(lp)]
            tris += [(p + n, q + n, q), (p + n, q, p)]
    info = f"outline points {'+'.join(str(len(lp)) for lp in loops)}"
    return verts, np.array(tris), info


# ----------------------------------------------------------------------------------------------
# Dragon: signed distance primitives, smooth union, marching tetrahedra, decimation.

def smin(a, b, k):
    h = np.maximum(k - np.abs(a - b), 0.0) / k
    return np.minimum(a, b) - h * h * k / 4


def sd_ellipsoid(p, c, r, axes=None):
    q = p - np.asarray(c, float)
    if axes is not None:
        q = q @ np.asarray(axes, float).T
    q = q / np.asarray(r, float)
    k0 = np.linalg.norm(q, axis=-1)
    k1 = np.linalg.norm(q / np.asarray(r, float), axis=-1)
    return k0 * (k0 - 1) / np.maximum(k1, 1e-12)


def sd_tube(p, pts, radii):
    """Union of tapered capsules along a polyline (radius interpolated linearly)."""
    d = np.full(p.shape[:-1], np.inf)
    for k in range(len(pts) - 1):
        a, b = np.asarray(pts[k], float), np.asarray(pts[k + 1], float)
        ba = b - a
        t = np.clip(((p - a) @ ba) / (ba @ ba), 0.0, 1.0)
        rad = radii[k] + (radii[k + 1] - radii[k]) * t
        d = np.minimum(d, np.linalg.norm(p - a - t[..., None] * ba, axis=-1) - rad)
    return d


def bezier(ctrl, r0, r1, n=16):
    c = np.asarray(ctrl, float)
    t = np.linspace(0, 1, n + 1)[:, None]
    deg = len(c) - 1
    pts = sum(math.comb(deg, i) * t ** i * (1 - t) ** (deg - i) * c[i] for i in range(deg + 1))
    return pts, list(r0 + (r1 - r0) * t[:, 0])


def wing_axes(side, tilt, sweep):
    """Local frame of a wing lobe: u along the body (swept back), v up and out, w its thickness."""
    v = np.array([0.0, side * math.sin(tilt), math.cos(tilt)])
    u = np.array([math.cos(sweep), 0.0, math.sin(sweep)])
    u -= (u @ v) * v
    u /= np.linalg.norm(u)
    return np.array([u, v, np.cross(u, v)])


def dragon_field(p):
    """Design coordinates (mm, before the final scaling to DRAGON_LENGTH): head at +x, soles on z = 0."""
    parts = []  # (distance, blend radius of the smooth union)
    parts.append((sd_ellipsoid(p, (-2, 0, 27), (30, 19, 16)), 0))             # body
    parts.append((sd_ellipsoid(p, (16, 0, 29), (15, 16, 15)), 6))             # chest
    for s in (-1, 1):
        parts.append((sd_ellipsoid(p, (-16, 12 * s, 23), (13, 8.5, 12)), 5))  # haunch
        parts.append((sd_tube(p, [(-16, 13 * s, 18), (-19, 13.5 * s, 9), (-16, 13.5 * s, 3)], [8, 7, 6.5]), 4))  # hind leg
        parts.append((sd_ellipsoid(p, (-13, 13.5 * s, 2.5), (9, 6.5, 4.5)), 3))  # hind foot
        parts.append((sd_ellipsoid(p, (17, 10 * s, 26), (9, 7.5, 9)), 5))     # shoulder
        parts.append((sd_tube(p, [(17, 11 * s, 22), (20, 12 * s, 11), (19, 12 * s, 3)], [7.5, 6.5, 6]), 4))  # front leg
        parts.append((sd_ellipsoid(p, (22, 12 * s, 2.5), (8.5, 6, 4.5)), 3))  # front foot
    neck, nr = bezier([(18, 0, 36), (30, 0, 40), (33, 0, 47)], 11, 8)
    parts.append((sd_tube(p, neck, nr), 5))
    parts.append((sd_ellipsoid(p, (37, 0, 50), (10.5, 9, 8.5)), 4))            # head
    parts.append((sd_tube(p, [(41, 0, 49), (49, 0, 46.5)], [7, 5]), 3))        # snout
    for s in (-1, 1):
        parts.append((sd_tube(p, [(33, 5 * s, 56), (28.5, 7.5 * s, 60.5), (25, 8.5 * s, 62)], [3, 2.3, 1.7]), 1.5))  # horn
        parts.append((sd_ellipsoid(p, (0, 14 * s, 48), (16, 14, 3.2), wing_axes(s, math.radians(30), math.radians(10))), 4))  # wing
        parts.append((sd_ellipsoid(p, (-15, 13 * s, 45), (10, 11, 3), wing_axes(s, math.radians(34), math.radians(35))), 3))  # its trailing lobe
    tail, tr = bezier([(-26, 0, 25), (-42, -2, 12), (-52, 6, 9), (-52, 16, 11)], 10, 3, n=24)
    parts.append((sd_tube(p, tail, tr), 5))
    f = parts[0][0]
    for d, k in parts[1:]:
        f = smin(f, d, k)
    return np.maximum(f, -p[..., 2])  # flat soles on z = 0


def marching_tetrahedra(f, origin, h):
    """Zero surface (inside f < 0) of the piecewise-linear interpolant of grid values f on the
    six-tetrahedra (Freudenthal) split of every cube; vertices welded by grid edge. The orientation
    of every triangle follows from the tetrahedron's orientation and its sign pattern, so it is
    outward even where the triangle is tiny."""
    nx, ny, nz = f.shape
    if (f[0] < 0).any() or (f[-1] < 0).any() or (f[:, 0] < 0).any() or (f[:, -1] < 0).any() \
            or (f[:, :, 0] < 0).any() or (f[:, :, -1] < 0).any():
        raise RuntimeError("shape touches the grid border")
    # keep vertices off the nodes (at least ~5 % of an edge away): values near zero are pushed to
    # +-0.1 h, which moves the surface by at most 0.1 h and avoids the worst slivers
    flat = np.where(np.abs(f) < 0.1 * h, np.where(f < 0, -0.1 * h, 0.1 * h), f).ravel()
    stride = np.array([ny * nz, nz, 1])
    i, j, k = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1), np.arange(nz - 1), indexing="ij")
    base = (i * stride[0] + j * stride[1] + k * stride[2]).ravel()
    unit = np.eye(3, dtype=int)

    def parity(seq):
        inv = sum(1 for x in range(4) for y in range(x + 1, 4) if seq[x] > seq[y])
        return -1 if inv % 2 else 1

    nn = flat.size
    tris_keys = []  # per case: (cases, 3 or 4) grid-edge keys lo * nn + hi of the polygon corners
    for perm in itertools.permutations(range(3)):
        offs = [np.zeros(3, int), unit[perm[0]], unit[perm[0]] + unit[perm[1]], np.ones(3, int)]
        orient = np.sign(np.linalg.det(np.array([offs[1], offs[2], offs[3]], float)))
        node = [base + int(o @ stride) for o in offs]
        code = sum((flat[node[v]] < 0).astype(int) << v for v in range(4))
        for cfg in range(1, 15):
            sel = np.nonzero(code == cfg)[0]
            if len(sel) == 0:
                continue
            ins = [v for v in range(4) if cfg >> v & 1]
            out = [v for v in range(4) if not cfg >> v & 1]
            if len(ins) in (1, 3):  # a triangle around the lone vertex, facing away from the inside
                lone = ins[0] if len(ins) == 1 else out[0]
                rest = [v for v in range(4) if v != lone]
                if (parity([lone] + rest) * orient < 0) != (len(ins) == 3):
                    rest[1], rest[2] = rest[2], rest[1]
                poly = [(lone, rest[0]), (lone, rest[1]), (lone, rest[2])]
            else:  # a quad separating edge p-q (inside) from edge r-s (outside)
                p_, q_ = ins
                r_, s_ = out
                if parity([p_, q_, r_, s_]) * orient < 0:
                    r_, s_ = s_, r_
                poly = [(p_, r_), (p_, s_), (q_, s_), (q_, r_)]
            a = np.stack([node[e[0]][sel] for e in poly], 1).astype(np.int64)
            b = np.stack([node[e[1]][sel] for e in poly], 1).astype(np.int64)
            tris_keys.append(np.minimum(a, b) * nn + np.maximum(a, b))
    # vertices
    allkeys = np.concatenate([t.ravel() for t in tris_keys])
    ukeys, inv = np.unique(allkeys, return_inverse=True)
    a, b = ukeys // nn, ukeys % nn
    fa, fb = flat[a], flat[b]
    t = fa / (fa - fb)

    def coords(n):
        return np.column_stack([n // stride[0], (n // stride[1]) % ny, n % nz]) * h + origin

    V = coords(a) + t[:, None] * (coords(b) - coords(a))
    tris = []
    pos = 0
    for tk in tris_keys:
        m, w = tk.shape
        ids = inv[pos:pos + m * w].reshape(m, w)
        pos += m * w
        if w == 3:
            tris.append(ids)
        else:  # planar convex quad: split along the shorter diagonal
            d02 = np.linalg.norm(V[ids[:, 0]] - V[ids[:, 2]], axis=1)
            d13 = np.linalg.norm(V[ids[:, 1]] - V[ids[:, 3]], axis=1)
            use02 = d02 <= d13
            q = ids[use02]
            tris += [q[:, [0, 1, 2]], q[:, [0, 2, 3]]]
            q = ids[~use02]
            tris += [q[:, [0, 1, 3]], q[:, [1, 2, 3]]]
    return V, np.concatenate(tris)


def decimate(V, T, target, min_edge):
    """Quadric-error edge collapses (Garland & Heckbert) with a small edge-length term, keeping the
    surface a closed 2-manifold (link condition) and rejecting collapses that flip or crush a
    triangle, until at most `target` triangles remain; edges shorter than `min_edge` go first, and
    all of them (where allowed)."""
    V = [np.array(v, float) for v in V]
    faces = [list(map(int, t)) for t in T]
    alive = [True] * len(faces)
    vf = [set() for _ in V]
    for fi, t in enumerate(faces):
        for v in t:
            vf[v].add(fi)
    Q = [np.zeros((4, 4)) for _ in V]
    for t in faces:
        a, b, c = V[t[0]], V[t[1]], V[t[2]]
        n = np.cross(b - a, c - a)
        area2 = np.linalg.norm(n)
        if area2 < 1e-14:
            continue
        n = n / area2
        pl = np.append(n, -n @ a)
        K = np.outer(pl, pl) * area2 / 2
        for v in t:
            Q[v] += K
    stamp = [0] * len(V)
    mean_area = sum(np.linalg.norm(np.cross(V[t[1]] - V[t[0]], V[t[2]] - V[t[0]])) / 2 for t in faces) / len(faces)
    alpha = 0.02

    def plan(u, w):
        K = Q[u] + Q[w]
        mid = (V[u] + V[w]) / 2
        cands = [V[u], V[w], mid]
        A = K[:3, :3] + 1e-6 * mean_area * np.eye(3)
        try:
            x = np.linalg.solve(A, -K[:3, 3] + 1e-6 * mean_area * mid)
            if np.linalg.norm(x - mid) < np.linalg.norm(V[u] - V[w]):
                cands.append(x)
        except np.linalg.LinAlgError:
            pass
        best = None
        for x in cands:
            xh = np.append(x, 1.0)
            err = xh @ K @ xh
            if best is None or err < best[0]:
                best = (err, x)
        L2 = float(np.sum((V[u] - V[w]) ** 2))
        return max(best[0], 0.0) + alpha * L2 * L2, best[1]

    heap = []

    def push(u, w):
        if u > w:
            u, w = w, u
        cost, x = plan(u, w)
        short = float(np.sum((V[u] - V[w]) ** 2)) < min_edge * min_edge
        heapq.heappush(heap, (not short, cost, u, w, stamp[u], stamp[w], tuple(x)))

    def nbrs(u):
        s = set()
        for fi in vf[u]:
            s.update(faces[fi])
        s.discard(u)
        return s

    for fi, t in enumerate(faces):
        for k in range(3):
            if t[k] < t[(k + 1) % 3]:
                push(t[k], t[(k + 1) % 3])
    nfaces = len(faces)
    blocked = [set() for _ in V]  # rejected collapse partners
    while heap and (nfaces > target or not heap[0][0]):
        _, cost, u, w, su, sw, x = heapq.heappop(heap)
        if stamp[u] != su or stamp[w] != sw or not vf[u] or not vf[w]:
            continue
        shared = vf[u] & vf[w]
        if len(shared) != 2:
            continue
        opp = set()
        for fi in shared:
            opp.update(faces[fi])
        opp -= {u, w}
        if nbrs(u) & nbrs(w) != opp or len(opp) != 2:
            continue
        x = np.array(x)
        ok = True
        for fi in (vf[u] | vf[w]) - shared:
            t = faces[fi]
            old = [V[v] for v in t]
            new = [x if v in (u, w) else V[v] for v in t]
            n0 = np.cross(old[1] - old[0], old[2] - old[0])
            n1 = np.cross(new[1] - new[0], new[2] - new[0])
            l0, l1 = np.linalg.norm(n0), np.linalg.norm(n1)
            if l1 < 1e-12 or (l0 > 1e-12 and n0 @ n1 <= 0.5 * l0 * l1):
                ok = False
                break
            l2 = sum(float(np.sum((new[k] - new[(k + 1) % 3]) ** 2)) for k in range(3))
            q0 = 2 * math.sqrt(3) * l0 / max(sum(float(np.sum((old[k] - old[(k + 1) % 3]) ** 2)) for k in range(3)), 1e-30)
            if 2 * math.sqrt(3) * l1 / l2 < min(0.08, q0):
                ok = False
                break
        if not ok:  # retried when something around it changes
            blocked[u].add(w)
            blocked[w].add(u)
            continue
        for fi in shared:
            alive[fi] = False
            for v in faces[fi]:
                vf[v].discard(fi)
            nfaces -= 1
        for fi in list(vf[w]):
            faces[fi] = [u if v == w else v for v in faces[fi]]
            vf[u].add(fi)
        vf[w] = set()
        V[u] = x
        Q[u] = Q[u] + Q[w]
        stamp[u] += 1
        stamp[w] += 1
        ring = nbrs(u)
        for n_ in ring:
            push(u, n_)
        blocked[u] |= blocked[w]
        blocked[w] = set()
        for a in ring | {u}:
            for b in blocked[a]:
                if vf[b] and b != u:
                    push(a, b)
            blocked[a] = set()
    used = sorted({v for fi, t in enumerate(faces) if alive[fi] for v in t})
    remap = {v: i for i, v in enumerate(used)}
    V2 = np.array([V[v] for v in used])
    T2 = np.array([[remap[v] for v in t] for fi, t in enumerate(faces) if alive[fi]])
    return V2, T2


def dragon():
    h = DRAGON_GRID
    # odd offsets keep the grid nodes off the primitives' round-number extremes; no node on z = 0
    lo, hi = np.array([-66.0 + 0.37 * h, -30.0 + 0.29 * h, -h / 2 - 2 * h]), np.array([62.0, 30.0, 70.0])
    n = np.ceil((hi - lo) / h).astype(int) + 1
    axes = [lo[d] + h * np.arange(n[d]) for d in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1)
    f = dragon_field(grid)
    V, T = marching_tetrahedra(f, lo, h)
    n_mt = len(T)
    V, T = decimate(V, T, DRAGON_TRIANGLES, 0.2 * h)
    size = V.max(0) - V.min(0)
    V = V * (DRAGON_LENGTH / size[0])
    c = (V.min(0) + V.max(0)) / 2
    V -= np.array([c[0], c[1], V[:, 2].min()])
    return V, T, f"marching tetrahedra {n_mt} triangles"


# ----------------------------------------------------------------------------------------------
# Checks and output.

def obj_text(name, V, T):
    lines = [f"# {name}, millimetres, generated by make_paper_meshes.py\n"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in V]
    lines += [f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in T]
    return "".join(lines)


def parse_obj(text):
    V, T = [], []
    for line in text.splitlines():
        w = line.split()
        if w and w[0] == "v":
            V.append([float(x) for x in w[1:4]])
        elif w and w[0] == "f":
            T.append([int(x) - 1 for x in w[1:4]])
    return np.array(V), np.array(T, dtype=np.int64)


def seg_hits_tri(p0, p1, a, b, c, eps):
    d = p1 - p0
    e1, e2 = b - a, c - a
    hv = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, hv)
    scale = np.linalg.norm(d, axis=1) * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)
    ok = np.abs(det) > 1e-12 * scale
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = p0 - a
    u = np.einsum("ij,ij->i", s, hv) * inv
    q = np.cross(s, e1)
    v = np.einsum("ij,ij->i", d, q) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    return ok & (u >= -eps) & (v >= -eps) & (u + v <= 1 + eps) & (t >= -eps) & (t <= 1 + eps)


def self_intersections(V, T):
    """Pairs of triangles that intersect other than along their shared edge or vertex. Pairs
    with no common vertex count when an edge of one meets the other (touching counts); pairs with
    one common vertex when the edge opposite it meets the other. Coplanar overlaps are not seen
    (the digit caps are checked separately for that)."""
    tv = V[T]
    lo, hi = tv.min(1), tv.max(1)
    cell = float((hi - lo).max()) + 1e-6
    ilo = np.floor(lo / cell).astype(np.int64)
    ihi = np.floor(hi / cell).astype(np.int64)
    tri_ids, keys = [], []
    for dx, dy, dz in itertools.product((0, 1), repeat=3):
        c = np.column_stack([np.where(dx, ihi[:, 0], ilo[:, 0]), np.where(dy, ihi[:, 1], ilo[:, 1]), np.where(dz, ihi[:, 2], ilo[:, 2])])
        tri_ids.append(np.arange(len(T)))
        keys.append((c[:, 0] * 1000003 + c[:, 1]) * 1000003 + c[:, 2])
    tri_ids, keys = np.concatenate(tri_ids), np.concatenate(keys)
    pk = np.unique(keys * len(T) + tri_ids)
    keys, tri_ids = pk // len(T), pk % len(T)
    starts = np.nonzero(np.r_[True, keys[1:] != keys[:-1]])[0]
    ends = np.r_[starts[1:], len(keys)]
    pairs = []
    for s, e in zip(starts, ends):
        if e - s > 1:
            i, j = np.triu_indices(e - s, 1)
            pairs.append(tri_ids[s + i] * len(T) + tri_ids[s + j])
    if not pairs:
        return 0
    pairs = np.unique(np.concatenate(pairs))
    A, B = pairs // len(T), pairs % len(T)
    overlap = np.all((lo[A] <= hi[B] + 1e-9) & (lo[B] <= hi[A] + 1e-9), axis=1)
    A, B = A[overlap], B[overlap]
    common = (T[A][:, :, None] == T[B][:, None, :])
    ncommon = common.sum((1, 2))
    hits = 0
    for lo_i in range(0, len(A), 200000):
        a, b, nc = A[lo_i:lo_i + 200000], B[lo_i:lo_i + 200000], ncommon[lo_i:lo_i + 200000]
        m0 = nc == 0
        a0, b0 = a[m0], b[m0]
        hit = np.zeros(len(a0), bool)
        for X, Y in ((a0, b0), (b0, a0)):
            for k in range(3):
                hit |= seg_hits_tri(V[T[X, k]], V[T[X, (k + 1) % 3]], V[T[Y, 0]], V[T[Y, 1]], V[T[Y, 2]], 1e-9)
        hits += int(hit.sum())
        m1 = nc == 1
        a1, b1 = a[m1], b[m1]
        if len(a1):
            c = common[lo_i:lo_i + 200000][m1]
            hit = np.zeros(len(a1), bool)
            for X, Y, ax in ((a1, b1, 2), (b1, a1, 1)):
                k = np.argmax(c.any(axis=ax), axis=1)  # slot of the shared vertex in X
                r = np.arange(len(X))
                p0, p1 = V[T[X][r, (k + 1) % 3]], V[T[X][r, (k + 2) % 3]]
                hit |= seg_hits_tri(p0, p1, V[T[Y, 0]], V[T[Y, 1]], V[T[Y, 2]], -1e-9)
            hits += int(hit.sum())
    return hits


def check_mesh(name, V, T):
    """Problems of a triangle mesh (empty if it is a closed, outward, clean 2-manifold) and facts."""
    problems = []
    nv, nt = len(V), len(T)
    if T.min() < 0 or T.max() >= nv:
        return [f"triangle index out of range"], {}
    if len(np.unique(T)) != nv:
        problems.append(f"{nv - len(np.unique(T))} unreferenced vertices")
    if np.any((T[:, 0] == T[:, 1]) | (T[:, 1] == T[:, 2]) | (T[:, 0] == T[:, 2])):
        problems.append("triangles with a repeated vertex")
    for arr, what in ((V, "double"), (V.astype(np.float32), "single")):
        if len(np.unique(arr, axis=0)) != nv:
            problems.append(f"vertices at the same position in {what} precision (not welded)")
    e = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
    key = e[:, 0] * nv + e[:, 1]
    ukey, cnt = np.unique(key, return_counts=True)
    if (cnt > 1).any():
        problems.append(f"{int((cnt > 1).sum())} directed edges used more than once (non-manifold or flipped)")
    rev = e[:, 1] * nv + e[:, 0]
    if not np.isin(rev, ukey).all():
        problems.append(f"{int((~np.isin(rev, ukey)).sum())} boundary edges (no reverse)")
    # one fan around every vertex: the link edges (b -> c) of triangles (v, b, c) form one cycle
    link = {}
    for a, b, c in T.tolist():
        for v, p, q in ((a, b, c), (b, c, a), (c, a, b)):
            link.setdefault(v, {})[p] = q
    bad_fans = 0
    for v, m in link.items():
        start = next(iter(m))
        p, steps = start, 0
        while p in m and steps <= len(m):
            p = m[p]
            steps += 1
            if p == start:
                break
        if p != start or steps != len(m):
            bad_fans += 1
    if bad_fans:
        problems.append(f"{bad_fans} non-manifold vertices")
    # connected pieces
    parent = list(range(nv))

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for a, b, c in T.tolist():
        ra, rb, rc = find(a), find(b), find(c)
        parent[rb] = ra
        parent[find(rc)] = ra
    pieces = len({find(v) for v in range(nv)})
    if pieces != 1:
        problems.append(f"{pieces} connected pieces")
    p0, p1, p2 = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    cr = np.cross(p1 - p0, p2 - p0)
    area = np.linalg.norm(cr, axis=1) / 2
    ndeg = int((area < DEGENERATE_AREA).sum())
    if ndeg:
        problems.append(f"{ndeg} degenerate triangles (area < {DEGENERATE_AREA} mm^2)")
    vol = float(np.einsum("ij,ij->i", p0, np.cross(p1, p2)).sum() / 6)
    if not vol > 0:
        problems.append(f"signed volume {vol} is not positive (inward normals)")
    nsi = self_intersections(V, T)
    if nsi:
        problems.append(f"{nsi} self-intersecting triangle pairs")
    limit = MAX_TRIANGLES.get(name)
    if limit and nt >= limit:
        problems.append(f"{nt} triangles, the budget is < {limit}")
    if nt < MIN_TRIANGLES.get(name, 0):
        problems.append(f"{nt} triangles, fewer than {MIN_TRIANGLES[name]}")
    euler = nv - len(ukey) // 2 + nt
    edge_len = np.linalg.norm(V[e[:, 1]] - V[e[:, 0]], axis=1)
    facts = {"volume": vol, "genus": (2 - euler) // 2 if pieces == 1 else None, "degenerate": ndeg,
             "min_area": float(area.min()), "min_edge": float(edge_len.min()), "self_intersections": nsi}
    return problems, facts


def emit(name, V, T, info=""):
    text = obj_text(name, V, T)
    V2, T2 = parse_obj(text)  # check exactly what the file holds
    problems, facts = check_mesh(name, V2, T2)
    lo, hi = V2.min(0), V2.max(0)
    size = hi - lo
    print(f"{name}.obj: {len(T2)} triangles, {len(V2)} vertices, "
          f"bbox {size[0]:.2f} x {size[1]:.2f} x {size[2]:.2f} mm "
          f"(x {lo[0]:.2f}..{hi[0]:.2f}, y {lo[1]:.2f}..{hi[1]:.2f}, z {lo[2]:.2f}..{hi[2]:.2f}), "
          f"volume {facts.get('volume', float('nan')):.1f} mm^3")
    print(f"    genus {facts.get('genus')}, degenerate triangles {facts.get('degenerate')}, "
          f"self-intersections {facts.get('self_intersections')}, "
          f"smallest triangle {facts.get('min_area', 0):.3g} mm^2, shortest edge {facts.get('min_edge', 0):.3g} mm"
          + (f", {info}" if info else ""))
    if problems:
        sys.exit(f"make_paper_meshes.py: {name} is broken: " + "; ".join(problems))
    with open(os.path.join(HERE, name + ".obj"), "w") as f:
        f.write(text)


if __name__ == "__main__":
    emit("bowl", *bowl())
    for ch in "208":
        emit(f"digit_{ch}", *digit(ch))
    emit("dragon", *dragon())

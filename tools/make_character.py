#!/usr/bin/python3
"""Makes the demo character (demos/meshes/character.glb): a 1.7 m humanoid, rigged and animated.

    /usr/bin/python3 tools/make_character.py [--out demos/meshes/character.glb]

The render mesh is what an artist's often is: a soup of closed parts (ellipsoids and tapered
capsules for pelvis, belly, chest, neck, head, arms, hands, thighs, shins and feet) that overlap
and intersect, so nothing downstream may assume one closed manifold surface. Y is up, the
character faces +z, its left is +x (glTF's convention). Twenty-one joints, parents first:

    hips (the root) > spine > chest > neck > head
                            > chest > upper_arm_l > forearm_l > hand_l   (and _r)
    hips > thigh_l > shin_l > foot_l > toes_l, heel_l                   (and _r)

Skin weights: each vertex's four nearest bones (a bone: the segment from its joint to its child,
or a point for a leaf), weighted by 1 / (d + 1 cm)^6 and normalised, so that parts blend over a
few centimetres about each joint. Inverse bind matrices: the inverses of the joints' rest globals.

Two clips, LINEAR, keyed at 30 per second:
- "walk" (1 s, a cycle: loops): walking in place. Thighs swing +-20 degrees out of phase, a knee
  bends up to 50 degrees while its leg swings forward, the ankles keep the feet flat, the hips sink
  so that the lower foot stays on the ground (y = 0), the arms swing against the legs, the spine
  and chest counter-twist 5 degrees.
- "jump" (1.5 s): crouch (thighs 50 degrees, knees 90, torso leaning 20, arms back), push off,
  a flight that lifts the feet 15 cm, a landing absorbed into a half crouch, and rest.
"""
import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from glb import Glb  # noqa: E402
from run_file import write_whole  # noqa: E402

# Joint name, parent, rest position (m).
JOINTS = [
    ("hips", None, (0.0, 0.95, 0.0)),
    ("spine", "hips", (0.0, 1.10, 0.0)),
    ("chest", "spine", (0.0, 1.30, 0.0)),
    ("neck", "chest", (0.0, 1.50, 0.0)),
    ("head", "neck", (0.0, 1.60, 0.0)),
]
for side, s in (("l", 1.0), ("r", -1.0)):
    JOINTS += [
        (f"upper_arm_{side}", "chest", (s * 0.19, 1.42, 0.0)),
        (f"forearm_{side}", f"upper_arm_{side}", (s * 0.38, 1.23, 0.0)),
        (f"hand_{side}", f"forearm_{side}", (s * 0.555, 1.055, 0.0)),
    ]
for side, s in (("l", 1.0), ("r", -1.0)):
    JOINTS += [
        (f"thigh_{side}", "hips", (s * 0.10, 0.92, 0.0)),
        (f"shin_{side}", f"thigh_{side}", (s * 0.10, 0.50, 0.0)),
        (f"foot_{side}", f"shin_{side}", (s * 0.10, 0.08, 0.0)),
        (f"toes_{side}", f"foot_{side}", (s * 0.10, 0.03, 0.11)),
        (f"heel_{side}", f"foot_{side}", (s * 0.10, 0.035, -0.03)),
    ]
NAMES = [j[0] for j in JOINTS]
INDEX = {n: i for i, n in enumerate(NAMES)}
PARENT = [INDEX[p] if p else -1 for _, p, _ in JOINTS]
REST = np.array([p for _, _, p in JOINTS])
THIGH, SHIN = 0.42, 0.42  # m: hip to knee, knee to ankle


def ring_frame(axis):
    axis = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    return axis, u, np.cross(axis, u)


def rings_to_mesh(rings, poles):
    """A closed surface from rings of equal size between two pole points (outward winding)."""
    n = len(rings[0])
    pts = [poles[0]] + [p for r in rings for p in r] + [poles[1]]
    tris = []
    for k in range(n):
        tris.append((0, 1 + (k + 1) % n, 1 + k))
    for r in range(len(rings) - 1):
        a, b = 1 + r * n, 1 + (r + 1) * n
        for k in range(n):
            k1 = (k + 1) % n
            tris += [(a + k, a + k1, b + k), (a + k1, b + k1, b + k)]
    last = 1 + (len(rings) - 1) * n
    for k in range(n):
        tris.append((len(pts) - 1, last + k, last + (k + 1) % n))
    return np.array(pts), np.array(tris)


def capsule(a, b, ra, rb, segments=16, cap_rings=4, body_rings=6):
    """A tapered capsule from a (radius ra) to b (radius rb)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d, u, v = ring_frame(b - a)
    circle = [math.cos(2 * math.pi * k / segments) * u + math.sin(2 * math.pi * k / segments) * v
              for k in range(segments)]
    rings = []
    for i in range(1, cap_rings + 1):  # the cap about a, from its pole
        phi = -math.pi / 2 + math.pi / 2 * i / cap_rings
        rings.append([a + ra * math.sin(phi) * d + ra * math.cos(phi) * c for c in circle])
    for i in range(1, body_rings):
        t = i / body_rings
        rings.append([(1 - t) * a + t * b + ((1 - t) * ra + t * rb) * c for c in circle])
    for i in range(cap_rings):
        phi = math.pi / 2 * i / cap_rings
        rings.append([b + rb * math.sin(phi) * d + rb * math.cos(phi) * c for c in circle])
    return rings_to_mesh(rings, [a - ra * d, b + rb * d])


def ellipsoid(c, radii, segments=16, rings=10):
    c, radii = np.asarray(c, float), np.asarray(radii, float)
    out = []
    for i in range(1, rings):
        phi = -math.pi / 2 + math.pi * i / rings
        out.append([c + radii * np.array([math.cos(phi) * math.cos(2 * math.pi * k / segments), math.sin(phi),
                                          math.cos(phi) * math.sin(2 * math.pi * k / segments)])
                    for k in range(segments)])
    pts, tris = rings_to_mesh(out, [c - radii * [0, 1, 0], c + radii * [0, 1, 0]])
    return pts, tris[:, ::-1]  # rings run up the y axis with k turning x to z: flip to outward


def parts():
    p = [ellipsoid((0, 0.95, 0), (0.17, 0.12, 0.11)),
         ellipsoid((0, 1.12, 0.01), (0.155, 0.13, 0.115)),
         ellipsoid((0, 1.32, 0), (0.18, 0.16, 0.11)),
         capsule((0, 1.44, 0), (0, 1.58, 0.01), 0.055, 0.05),
         ellipsoid((0, 1.68, 0.01), (0.09, 0.12, 0.10))]
    for s in (1.0, -1.0):
        p += [capsule((s * 0.17, 1.43, 0), (s * 0.38, 1.23, 0), 0.055, 0.045),
              capsule((s * 0.38, 1.23, 0), (s * 0.54, 1.07, 0), 0.042, 0.033),
              ellipsoid((s * 0.59, 1.02, 0), (0.04, 0.06, 0.025)),
              capsule((s * 0.10, 0.88, 0), (s * 0.10, 0.50, 0), 0.085, 0.055),
              capsule((s * 0.10, 0.50, 0), (s * 0.10, 0.09, 0), 0.052, 0.038),
              ellipsoid((s * 0.10, 0.04, 0.05), (0.045, 0.04, 0.12))]
    pts, tris = [], []
    for x, t in p:
        tris.append(t + sum(len(q) for q in pts))
        pts.append(x)
    return np.vstack(pts), np.vstack(tris)


def bone_segments():
    """Each joint's bone: joint to the mean of its children (a leaf: its own point)."""
    segs = []
    for j in range(len(NAMES)):
        kids = [k for k in range(len(NAMES)) if PARENT[k] == j]
        end = REST[kids].mean(axis=0) if kids and NAMES[j] != "hips" else REST[j]
        if NAMES[j] in ("hand_l", "hand_r", "head"):
            end = REST[j] + (REST[j] - REST[PARENT[j]]) * 0.5
        if NAMES[j].startswith("toes"):
            end = REST[j] + np.array([0, 0.0, 0.05])
        if NAMES[j].startswith("heel"):
            end = REST[j] + np.array([0, 0.0, -0.02])
        segs.append((REST[j], end))
    return segs


def skin_weights(x):
    d = np.empty((len(x), len(NAMES)))
    for j, (a, b) in enumerate(bone_segments()):
        ab = b - a
        t = np.clip(((x - a) @ ab) / max(ab @ ab, 1e-12), 0, 1) if ab @ ab > 0 else np.zeros(len(x))
        d[:, j] = np.linalg.norm(x - (a + t[:, None] * ab), axis=1)
    w = 1.0 / (d + 0.01) ** 6
    top = np.argsort(-w, axis=1)[:, :4]
    tw = np.take_along_axis(w, top, axis=1)
    return top.astype(np.uint16), (tw / tw.sum(axis=1, keepdims=True)).astype(np.float32)


def quat_x(deg):
    h = math.radians(deg) / 2
    return (math.sin(h), 0.0, 0.0, math.cos(h))  # glTF order: x, y, z, w


def quat_y(deg):
    h = math.radians(deg) / 2
    return (0.0, math.sin(h), 0.0, math.cos(h))


def hips_drop(legs):
    """The hips' fall that keeps the lower foot on the ground: legs = [(thigh, knee) degrees]."""
    reach = max(THIGH * math.cos(math.radians(a)) + SHIN * math.cos(math.radians(a - k)) for a, k in legs)
    return reach - (THIGH + SHIN)


def leg_pose(pose, side, thigh, knee):
    """Thigh flexion forward, knee flexion backward, the ankle keeping the foot flat."""
    pose[f"thigh_{side}"] = quat_x(-thigh)
    pose[f"shin_{side}"] = quat_x(knee)
    pose[f"foot_{side}"] = quat_x(thigh - knee)


def walk_pose(t):
    pose = {}
    phase = 2 * math.pi * t
    legs = []
    for side, shift in (("l", 0.0), ("r", math.pi)):
        thigh = 20 * math.sin(phase + shift)
        knee = 50 * max(0.0, math.cos(phase + shift)) ** 2
        leg_pose(pose, side, thigh, knee)
        legs.append((thigh, knee))
        arm = -0.6 * thigh
        pose[f"upper_arm_{side}"] = quat_x(-arm)
        pose[f"forearm_{side}"] = quat_x(-10 - max(0.0, arm))
    pose["spine"] = quat_y(5 * math.sin(phase))
    pose["chest"] = quat_y(-5 * math.sin(phase))
    return pose, (0.0, hips_drop(legs), 0.0)


JUMP_KEYS = [  # time, thigh, knee, torso lean, arm flexion, hips lift above the feet-on-ground height
    (0.0, 0, 0, 0, 0, 0.0),
    (0.4, 50, 90, 20, -40, 0.0),
    (0.6, 0, 0, 0, 90, 0.05),
    (0.8, 20, 30, 0, 60, 0.15),
    (1.0, 0, 0, 0, 20, 0.0),
    (1.2, 30, 60, 10, 0, 0.0),
    (1.5, 0, 0, 0, 0, 0.0),
]


def jump_pose(t):
    k = max(i for i in range(len(JUMP_KEYS)) if JUMP_KEYS[i][0] <= t + 1e-12)
    k1 = min(k + 1, len(JUMP_KEYS) - 1)
    t0, t1 = JUMP_KEYS[k][0], JUMP_KEYS[k1][0]
    s = 0.0 if k1 == k else (t - t0) / (t1 - t0)
    s = 0.5 - 0.5 * math.cos(math.pi * s)  # eased between keys
    thigh, knee, lean, arm, lift = ((1 - s) * np.array(JUMP_KEYS[k][1:]) + s * np.array(JUMP_KEYS[k1][1:]))
    pose = {}
    for side in ("l", "r"):
        leg_pose(pose, side, thigh, knee)
        pose[f"upper_arm_{side}"] = quat_x(-arm)
    pose["spine"] = quat_x(lean)
    return pose, (0.0, hips_drop([(thigh, knee)]) + lift, 0.0)


def add_clip(g, name, pose_at, duration, rate=30):
    times = np.arange(int(round(duration * rate)) + 1) / rate
    poses = [pose_at(t) for t in times]
    t_acc = g.accessor(times.astype(np.float32), bounds=True)
    samplers, channels = [], []
    animated = sorted({n for p, _ in poses for n in p}, key=INDEX.get)
    for n in animated:
        q = np.array([p.get(n, (0, 0, 0, 1)) for p, _ in poses], np.float32)
        samplers.append({"input": t_acc, "output": g.accessor(q), "interpolation": "LINEAR"})
        channels.append({"sampler": len(samplers) - 1, "target": {"node": 1 + INDEX[n], "path": "rotation"}})
    lift = np.array([REST[0] + np.array(h) for _, h in poses], np.float32)
    samplers.append({"input": t_acc, "output": g.accessor(lift), "interpolation": "LINEAR"})
    channels.append({"sampler": len(samplers) - 1, "target": {"node": 1, "path": "translation"}})
    g.gltf.setdefault("animations", []).append({"name": name, "samplers": samplers, "channels": channels})


def build():
    x, tris = parts()
    joints, weights = skin_weights(x)
    g = Glb()
    prim = {"attributes": {"POSITION": g.accessor(x.astype(np.float32), bounds=True, target=34962),
                           "JOINTS_0": g.accessor(joints, component=5123, target=34962),
                           "WEIGHTS_0": g.accessor(weights, target=34962)},
            "indices": g.triangles(tris)}
    g.mesh(prim, name="body")
    g.node(name="body", mesh=0, skin=0)
    for j, (name, parent, pos) in enumerate(JOINTS):
        local = np.array(pos) - (REST[PARENT[j]] if PARENT[j] >= 0 else 0)
        kids = [1 + k for k in range(len(NAMES)) if PARENT[k] == j]
        g.node(name=name, translation=[float(v) for v in local], **({"children": kids} if kids else {}))
    ibm = np.zeros((len(NAMES), 16), np.float32)
    for j in range(len(NAMES)):
        m = np.eye(4)
        m[:3, 3] = -REST[j]
        ibm[j] = m.T.reshape(-1)  # column-major
    g.gltf["skins"] = [{"name": "skeleton", "skeleton": 1, "joints": [1 + j for j in range(len(NAMES))],
                        "inverseBindMatrices": g.accessor(ibm, per=16)}]
    g.gltf["scenes"] = [{"nodes": [0, 1]}]
    add_clip(g, "walk", walk_pose, 1.0)
    add_clip(g, "jump", jump_pose, 1.5)
    return g, len(x), len(tris)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), os.pardir, "demos", "meshes",
                                                  "character.glb"))
    a = ap.parse_args()
    g, nv, nt = build()
    data = g.to_bytes()
    write_whole(a.out, lambda f: f.write(data), "wb")
    print(f"wrote {os.path.relpath(a.out)}: {nv} vertices, {nt} triangles, {len(NAMES)} joints, clips walk and jump "
          f"({len(data) // 1024} KiB)")


if __name__ == "__main__":
    main()

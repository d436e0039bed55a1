#!/usr/bin/env python3
"""Generates robots/hrp2/hrp2.urdf and robots/hrp2/hrp2.yaml: an HRP-2-class model built from
published figures (../shared/notes/robot-facts.md, robots/hrp2/README.md) and stated estimates.

Link masses and centres of mass are estimates ([est]) distributed to match the published segment
sums; inertias are those of the listed primitive shapes (solid boxes / cylinders) about the CoM.
Run:  python3 tools/gen_hrp2.py  (rewrites both files; the model tests load what it writes).
"""
import math
import os
import sys

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "robots", "hrp2")

def box_inertia(m, sx, sy, sz):
    return (m * (sy * sy + sz * sz) / 12.0, m * (sx * sx + sz * sz) / 12.0, m * (sx * sx + sy * sy) / 12.0)

def cyl_inertia(m, r, l):  # axis along z
    ixx = m * (3 * r * r + l * l) / 12.0
    return (ixx, ixx, 0.5 * m * r * r)

# ---------------------------------------------------------------- links
# name: (mass kg [est], com xyz in link frame [est], shape, shape origin xyz)
# shape: ("box", sx, sy, sz) or ("cylinder", r, l)  (axis z)
links = {}
def link(name, mass, com, shape, origin):
    links[name] = dict(mass=mass, com=com, shape=shape, origin=origin)

link("BODY", 14.5, (-0.01, 0.0, 0.12), ("box", 0.20, 0.24, 0.22), (0.0, 0.0, 0.08))
for side, s in (("R", -1.0), ("L", 1.0)):
    L = side + "LEG_"
    link(L + "LINK0", 0.80, (0.0, 0.0, 0.04), ("cylinder", 0.045, 0.08), (0.0, 0.0, 0.04))
    link(L + "LINK1", 0.90, (0.0, 0.0, 0.0), ("box", 0.10, 0.08, 0.08), (0.0, 0.0, 0.0))
    link(L + "LINK2", 3.20, (0.0, 0.0, -0.12), ("box", 0.11, 0.10, 0.30), (0.0, 0.0, -0.15))
    link(L + "LINK3", 1.70, (0.0, 0.0, -0.12), ("box", 0.09, 0.08, 0.28), (0.0, 0.0, -0.15))
    link(L + "LINK4", 0.35, (0.0, 0.0, 0.0), ("box", 0.06, 0.06, 0.06), (0.0, 0.0, 0.0))
    link(L + "LINK5", 0.25, (0.0, 0.0, -0.03), ("box", 0.08, 0.07, 0.05), (0.0, 0.0, -0.035))
    link(L + "ELASTIC_LINK", 0.02, (0.0, 0.0, 0.0), ("box", 0.02, 0.02, 0.02), (0.0, 0.0, 0.0))
    # sole rectangle +0.130/-0.100 in x, 0.075 outer / 0.056 inner in y; sole plane 0.035 below
    # the elastic joint (0.105 below the ankle axis); 2 cm thick plate
    link(L + "FOOT", 1.00, (0.015, s * 0.0095, -0.02), ("box", 0.23, 0.131, 0.02),
         (0.015, s * 0.0095, -0.025))
link("CHEST_LINK0", 1.2, (0.0, 0.0, 0.0), ("cylinder", 0.05, 0.06), (0.0, 0.0, 0.0))
link("CHEST_LINK1", 12.0, (-0.02, 0.0, 0.17), ("box", 0.22, 0.30, 0.30), (-0.03, 0.0, 0.15))
link("HEAD_LINK0", 0.5, (0.0, 0.0, 0.0), ("cylinder", 0.03, 0.05), (0.0, 0.0, 0.0))
link("HEAD_LINK1", 1.5, (0.0, 0.0, 0.10), ("box", 0.16, 0.16, 0.18), (0.0, 0.0, 0.10))
for side, s in (("R", -1.0), ("L", 1.0)):
    A = side + "ARM_"
    link(A + "LINK0", 0.80, (0.0, 0.0, 0.0), ("cylinder", 0.05, 0.08), (0.0, 0.0, 0.0))
    link(A + "LINK1", 0.60, (0.0, 0.0, 0.0), ("box", 0.08, 0.08, 0.08), (0.0, 0.0, 0.0))
    link(A + "LINK2", 1.55, (0.0, 0.0, -0.12), ("cylinder", 0.045, 0.22), (0.0, 0.0, -0.125))
    link(A + "LINK3", 1.25, (0.0, 0.0, -0.10), ("cylinder", 0.04, 0.20), (0.0, 0.0, -0.125))
    link(A + "LINK4", 0.60, (0.0, 0.0, 0.0), ("cylinder", 0.035, 0.05), (0.0, 0.0, 0.0))
    link(A + "LINK5", 0.60, (0.0, 0.0, -0.04), ("box", 0.06, 0.06, 0.08), (0.0, 0.0, -0.04))
    link(A + "LINK6", 0.50, (0.0, 0.0, -0.05), ("box", 0.05, 0.08, 0.10), (0.0, 0.0, -0.05))

# ---------------------------------------------------------------- joints
D = math.pi / 180.0
# name, parent, child, origin xyz, axis, right-side range (deg), vel rad/s, torque N m, gear, rotor kg m^2
leg = [  # [pub/open] robot-facts.md
    ("JOINT0", "BODY", "LINK0", (0, 0.060, 0), "z", (-45, 30), 3.54, 86, 384, 1.0e-6),
    ("JOINT1", "LINK0", "LINK1", (0, 0, 0), "x", (-35, 20), 3.81, 175, 240, 4.0e-6),
    ("JOINT2", "LINK1", "LINK2", (0, 0.035, 0), "y", (-125, 42), 4.42, 151, 180, 8.0e-6),
    ("JOINT3", "LINK2", "LINK3", (0, 0, -0.300), "y", (-2, 150), 3.98, 168, 200, 8.0e-6),
    ("JOINT4", "LINK3", "LINK4", (0, 0, -0.300), "y", (-75, 42), 5.08, 131, 180, 6.0e-6),
    ("JOINT5", "LINK4", "LINK5", (0, 0, 0), "x", (-20, 35), 9.14, 73, 100, 4.0e-6),
]
arm = [
    ("JOINT0", "CHEST_LINK1", "LINK0", (0, 0.250, 0.180), "y", (-180, 60), 4.17, 160, 219, 4.0e-6),
    ("JOINT1", "LINK0", "LINK1", (0, 0, 0), "x", (-95, 10), 2.42, 100, 231, 4.0e-6),
    ("JOINT2", "LINK1", "LINK2", (0, 0, 0), "z", (-92, 92), 4.16, 48, 267, 1.0e-6),
    ("JOINT3", "LINK2", "LINK3", (0, 0, -0.250), "y", (-137, 2), 2.24, 108, 250, 2.0e-6),
    ("JOINT4", "LINK3", "LINK4", (0, 0, -0.250), "z", (-92, 92), 4.73, 13.9, 145, 1.0e-6),
    ("JOINT5", "LINK4", "LINK5", (0, 0, 0), "y", (-92, 92), 3.17, 63, 350, 1.0e-6),
    ("JOINT6", "LINK5", "LINK6", (0, 0, -0.080), "x", (0, 45), 5.68, 3, 200, 1.0e-6),
]
# joints whose range mirrors between the right and left side (roll and yaw axes)
MIRROR = {("LEG", "JOINT0"), ("LEG", "JOINT1"), ("LEG", "JOINT5"), ("ARM", "JOINT1")}

joints = []  # dicts in HRP-2 order
def add_limb(side, s, kind, table):
    for (jn, parent, child, xyz, axis, rng, vel, tq, gear, rotor) in table:
        lo, hi = rng
        if side == "L" and (kind, jn) in MIRROR:
            lo, hi = -hi, -lo
        pname = parent if parent in ("BODY", "CHEST_LINK1") else side + kind + "_" + parent
        joints.append(dict(name=side + kind + "_" + jn, parent=pname, child=side + kind + "_" + child,
                           xyz=(xyz[0], s * xyz[1], xyz[2]), axis=axis, lo=lo, hi=hi, vel=vel,
                           torque=tq, gear=gear, rotor=rotor))

add_limb("R", -1.0, "LEG", leg)
add_limb("L", 1.0, "LEG", leg)
joints.append(dict(name="CHEST_JOINT0", parent="BODY", child="CHEST_LINK0", xyz=(0.032, 0, 0.3507),
                   axis="z", lo=-45, hi=45, vel=4.40, torque=151, gear=208, rotor=4.0e-6))
joints.append(dict(name="CHEST_JOINT1", parent="CHEST_LINK0", child="CHEST_LINK1", xyz=(0, 0, 0),
                   axis="y", lo=-5, hi=60, vel=2.40, torque=278, gear=382, rotor=4.0e-6))
joints.append(dict(name="HEAD_JOINT0", parent="CHEST_LINK1", child="HEAD_LINK0", xyz=(-0.007, 0, 0.2973),
                   axis="z", lo=-45, hi=45, vel=6.88, torque=9.6, gear=100, rotor=1.0e-6))
joints.append(dict(name="HEAD_JOINT1", parent="HEAD_LINK0", child="HEAD_LINK1", xyz=(0, 0, 0),
                   axis="y", lo=-30, hi=45, vel=6.88, torque=9.6, gear=100, rotor=1.0e-6))
add_limb("R", -1.0, "ARM", arm)
add_limb("L", 1.0, "ARM", arm)
assert len(joints) == 30

elastic = []
for side in ("R", "L"):
    elastic.append(dict(name=side + "LEG_ELASTIC_ROLL", parent=side + "LEG_LINK5",
                        child=side + "LEG_ELASTIC_LINK", xyz=(0, 0, -0.070), axis="x"))
    elastic.append(dict(name=side + "LEG_ELASTIC_PITCH", parent=side + "LEG_ELASTIC_LINK",
                        child=side + "LEG_FOOT", xyz=(0, 0, 0), axis="y"))

AX = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}

def f(v):
    return "%.6g" % v

def urdf():
    out = ['<?xml version="1.0"?>',
           "<!-- HRP-2-class humanoid built from published figures and estimates.",
           "     GENERATED by tools/gen_hrp2.py: edit the generator, not this file.",
           "     Not the manufacturer's model. Figures and sources: robots/hrp2/README.md -->",
           '<robot name="hrp2_class">']
    for name, l in links.items():
        m = l["mass"]
        sh = l["shape"]
        if sh[0] == "box":
            I = box_inertia(m, *sh[1:])
            geom = '<box size="%s %s %s"/>' % tuple(f(x) for x in sh[1:])
        else:
            I = cyl_inertia(m, *sh[1:])
            geom = '<cylinder radius="%s" length="%s"/>' % (f(sh[1]), f(sh[2]))
        o = " ".join(f(x) for x in l["origin"])
        out.append('  <link name="%s">' % name)
        out.append('    <inertial><origin xyz="%s" rpy="0 0 0"/><mass value="%s"/>' %
                   (" ".join(f(x) for x in l["com"]), f(m)))
        out.append('      <inertia ixx="%s" ixy="0" ixz="0" iyy="%s" iyz="0" izz="%s"/></inertial>' %
                   tuple(f(x) for x in I))
        out.append('    <visual><origin xyz="%s" rpy="0 0 0"/><geometry>%s</geometry></visual>' % (o, geom))
        out.append('    <collision><origin xyz="%s" rpy="0 0 0"/><geometry>%s</geometry></collision>' % (o, geom))
        out.append("  </link>")
    for j in joints:
        out.append('  <joint name="%s" type="revolute">' % j["name"])
        out.append('    <parent link="%s"/><child link="%s"/>' % (j["parent"], j["child"]))
        out.append('    <origin xyz="%s" rpy="0 0 0"/><axis xyz="%s"/>' %
                   (" ".join(f(x) for x in j["xyz"]), AX[j["axis"]]))
        out.append('    <limit lower="%s" upper="%s" velocity="%s" effort="%s"/>' %
                   (f(j["lo"] * D), f(j["hi"] * D), f(j["vel"]), f(j["torque"])))
        out.append("  </joint>")
    for j in elastic:
        out.append('  <!-- passive elastic ankle bushing (rotational spring/damper, robots/hrp2/hrp2.yaml) -->')
        out.append('  <joint name="%s" type="revolute">' % j["name"])
        out.append('    <parent link="%s"/><child link="%s"/>' % (j["parent"], j["child"]))
        out.append('    <origin xyz="%s" rpy="0 0 0"/><axis xyz="%s"/>' %
                   (" ".join(f(x) for x in j["xyz"]), AX[j["axis"]]))
        out.append('    <limit lower="-0.2" upper="0.2" velocity="10" effort="0"/>')
        out.append("  </joint>")
    out.append("</robot>")
    return "\n".join(out) + "\n"

HALF_SITTING = {  # deg [open: jrl-walkgen, sot-hrp2]
    "LEG": (0, 0, -26, 50, -24, 0), "CHEST": (0, 0), "HEAD": (0, 0),
    "RARM": (15, -10, 0, -30, 0, 0, 10), "LARM": (15, 10, 0, -30, 0, 0, 10)}

def half_sitting(name):
    if "LEG" in name:
        return HALF_SITTING["LEG"][int(name[-1])]
    if name.startswith("CHEST"):
        return 0
    if name.startswith("HEAD"):
        return 0
    return HALF_SITTING[name[:4]][int(name[-1])]

def safety_margin(name):
    # planner safety margin inside the mechanical range [est]: 5 deg; 2 deg for the gripper and the
    # chest pitch, whose half-sitting value (0) lies 5 deg from its lower limit
    return 2.0 if name.endswith("ARM_JOINT6") or name == "CHEST_JOINT1" else 5.0

def yaml():
    y = []
    y.append("# HRP-2-class robot: parameters beside hrp2.urdf. GENERATED by tools/gen_hrp2.py.")
    y.append("# Units: SI (m, kg, s, rad, N, N m) except where the key ends in _deg.")
    y.append("# Every figure and its source: robots/hrp2/README.md.  [pub] published, [open] open repo, [est] estimate")
    y.append("name: hrp2_class")
    y.append("urdf: hrp2.urdf              # relative to this file")
    y.append("base_link: BODY              # pelvis; floating base (6 coordinates, DART FreeJoint)")
    y.append("floating_base: true")
    y.append("gravity: 9.81                # m/s^2")
    y.append("")
    y.append("# 30 actuated joints in HRP-2 order. limits_deg: mechanical range [open];")
    y.append("# safety_margin_deg: the planner keeps this far inside it [est]; velocity rad/s, torque N m [open];")
    y.append("# gear_ratio [open]; rotor_inertia kg m^2 on the motor side [est, order 1e-6 as published].")
    y.append("actuated_joints:")
    for j in joints:
        y.append("  - {name: %s, limits_deg: [%s, %s], safety_margin_deg: %s, velocity: %s, torque: %s, "
                 "gear_ratio: %s, rotor_inertia: %s}" % (j["name"], f(j["lo"]), f(j["hi"]),
                                                         f(safety_margin(j["name"])), f(j["vel"]),
                                                         f(j["torque"]), f(j["gear"]), f(j["rotor"])))
    y.append("")
    y.append("# Passive elastic ankle bushings: rotational spring/damper per axis (seed section II-A).")
    y.append("# stiffness N m/rad: LAAS identification roll 707, pitch 502 [open: sot-torque-control];")
    y.append("# damping N m s/rad: poorly known, 10-65 in estimators [open]; 10 chosen [est]: the low")
    y.append("# end, and the largest the simulator's explicit bushing damper keeps stable at 1 ms")
    y.append("# (d dt <= 0.01; 12 already diverged in one of 7 step tests; sim/README.md).")
    y.append("elastic_joints:")
    for j in elastic:
        k = 707.0 if j["name"].endswith("ROLL") else 502.0
        y.append("  - {name: %s, stiffness: %s, damping: 10.0}" % (j["name"], f(k)))
    y.append("")
    y.append("# Feet. sole: frame at the ankle projection on the sole plane (on the foot body, below the bushing);")
    y.append("# sole rectangle relative to that frame [open: LAAS controllers]; force_sensor: 6-axis F/T frame at")
    y.append("# the elastic joint, on the ankle side of the bushing [est: position].")
    y.append("feet:")
    for side, key, s in (("R", "right", -1.0), ("L", "left", 1.0)):
        y.append("  %s:" % key)
        y.append("    link: %sLEG_FOOT" % side)
        y.append("    sole_frame: %s_sole" % key)
        y.append("    force_sensor_frame: %s_ft" % key)
        y.append("    sole: {x_front: 0.130, x_back: 0.100, y_outer: 0.075, y_inner: 0.056}")
    y.append("")
    y.append("# Named frames: parent link and fixed offset (xyz m, rpy rad).")
    y.append("frames:")
    y.append("  - {name: right_sole, link: RLEG_FOOT, xyz: [0, 0, -0.035], rpy: [0, 0, 0]}")
    y.append("  - {name: left_sole, link: LLEG_FOOT, xyz: [0, 0, -0.035], rpy: [0, 0, 0]}")
    y.append("  - {name: right_ft, link: RLEG_LINK5, xyz: [0, 0, -0.070], rpy: [0, 0, 0]}")
    y.append("  - {name: left_ft, link: LLEG_LINK5, xyz: [0, 0, -0.070], rpy: [0, 0, 0]}")
    y.append("  - {name: imu, link: CHEST_LINK1, xyz: [-0.13, 0, 0.118], rpy: [0, 0, 0]}   # [open: sot-hrp2]")
    y.append("  - {name: head, link: HEAD_LINK1, xyz: [0, 0, 0.10], rpy: [0, 0, 0]}")
    y.append("  - {name: pelvis, link: BODY, xyz: [0, 0, 0], rpy: [0, 0, 0]}")
    y.append("  - {name: torso, link: CHEST_LINK1, xyz: [0, 0, 0], rpy: [0, 0, 0]}")
    y.append("")
    y.append("# Collision capsules for the planner (segment p0-p1 in the link frame, radius) [est from shapes].")
    y.append("capsules:")
    caps = [("BODY", (0, 0, 0.0), (0, 0, 0.16), 0.13),
            ("CHEST_LINK1", (-0.03, 0, 0.08), (-0.03, 0, 0.22), 0.16),
            ("HEAD_LINK1", (0, 0, 0.06), (0, 0, 0.14), 0.09)]
    for side, s in (("R", -1.0), ("L", 1.0)):
        caps += [(side + "LEG_LINK2", (0, 0, -0.03), (0, 0, -0.27), 0.06),
                 (side + "LEG_LINK3", (0, 0, -0.03), (0, 0, -0.27), 0.05),
                 # The sole box (0.23 x 0.131 x 0.02 m, x -0.10..0.13) as three capsules along
                 # its inner edge, middle and outer edge, ending 1 cm inside its ends, radius
                 # sqrt(0.01^2 + 0.02^2 + 0.01^2) so that they reach its corners. One capsule of
                 # radius 0.03 on the middle line missed the edges: a swing foot rolled 0.33 rad
                 # hit the bar in the simulator while the planner's capsule cleared it (measured).
                 (side + "LEG_FOOT", (-0.09, s * 0.0095 - 0.0455, -0.025), (0.12, s * 0.0095 - 0.0455, -0.025), 0.0245),
                 (side + "LEG_FOOT", (-0.09, s * 0.0095, -0.025), (0.12, s * 0.0095, -0.025), 0.0245),
                 (side + "LEG_FOOT", (-0.09, s * 0.0095 + 0.0455, -0.025), (0.12, s * 0.0095 + 0.0455, -0.025), 0.0245),
                 (side + "ARM_LINK2", (0, 0, -0.02), (0, 0, -0.23), 0.05),
                 (side + "ARM_LINK3", (0, 0, -0.02), (0, 0, -0.23), 0.045),
                 (side + "ARM_LINK6", (0, 0, 0.0), (0, 0, -0.10), 0.045)]
    for (ln, p0, p1, r) in caps:
        y.append("  - {link: %s, p0: [%s], p1: [%s], radius: %s}" %
                 (ln, ", ".join(f(x) for x in p0), ", ".join(f(x) for x in p1), f(r)))
    y.append("")
    y.append("# Capsule link pairs the planner keeps apart besides the right leg's against the left leg's (from")
    y.append("# the kinematic tree): each hanging forearm and hand against its own thigh.")
    y.append("self_collision:")
    for side in ("R", "L"):
        for arm in ("LINK3", "LINK6"):
            y.append("  - [%sARM_%s, %sLEG_LINK2]" % (side, arm, side))
    y.append("")
    y.append("# Joint groups: truth files and overlays address joints by these names (and `all`).")
    y.append("joint_groups:")
    names = [j["name"] for j in joints]
    for group, prefixes in (("legs", ("RLEG_", "LLEG_")), ("arms", ("RARM_", "LARM_")),
                            ("chest", ("CHEST_",)), ("head", ("HEAD_",))):
        y.append("  %s: [%s]" % (group, ", ".join(n for n in names if n.startswith(prefixes))))
    y.append("")
    y.append("# Identification excitation (overstep plan --excite): joints swung about half-sitting, amplitude rad")
    y.append("# (times --amplitude), frequency Hz, phase rad. Incommensurate frequencies: the joints'")
    y.append("# velocities are not collinear (identifiability). The legs stay: the robot stands.")
    y.append("excitation:")
    for (jn, a, fr, ph) in (("CHEST_JOINT0", 0.15, 0.31, 0.0), ("CHEST_JOINT1", 0.06, 0.47, 1.0),
                            ("HEAD_JOINT0", 0.20, 0.73, 0.5), ("RARM_JOINT0", 0.40, 0.53, 0.0),
                            ("LARM_JOINT0", 0.40, 0.61, 2.0), ("RARM_JOINT3", 0.30, 0.89, 1.0),
                            ("LARM_JOINT3", 0.30, 1.07, 0.3), ("RARM_JOINT1", 0.10, 0.37, 0.7),
                            ("LARM_JOINT1", 0.10, 0.43, 1.9)):
        y.append("  - {joint: %s, amplitude: %s, frequency: %s, phase: %s}" % (jn, f(a), f(fr), f(ph)))
    y.append("")
    y.append("# Half-sitting posture, deg, HRP-2 joint order [open: jrl-walkgen, sot-hrp2].")
    y.append("half_sitting_deg: [%s]" % ", ".join(f(half_sitting(j["name"])) for j in joints))
    y.append("")
    y.append("# Joint acceleration limit used by planners [est: ~30 rad/s^2 in controllers].")
    y.append("acceleration_limit: 30.0")
    y.append("")
    y.append("# Stabilizer (stabilizer/README.md): every key optional, each checked against a safety range.")
    y.append("# Laws and typical gains: Kajita 2010 / hrpsys-base, Caron 2019 / mc_rtc [open]; tuned on")
    y.append("# the flexible-ankle pendulum in tests/unit/test_stabilizer.cpp [est].")
    y.append("stabilizer:")
    for key, val, comment in (
            ("feedback", "lipm", "lipm (Kajita 2010) or dcm (Caron 2019)"),
            # The plan's whole-body ZMP (its contact wrenches, with the angular momentum of the
            # whole-body motion), without the Tp x ZMP-rate feed-forward (that ZMP steps at the
            # contact switches): the stance CoPs stay within 3-7 mm of the plan's at p95, against
            # 10-17 mm with the table-cart ZMP and its feed-forward (docs/runtime.md).
            ("zmp_reference", "wholebody", "wholebody or tablecart (HRP-2's own stabilizer)"),
            ("zmp_feedforward", "0.0", "fraction of Tp x ZMP rate added to the command"),
            ("zmp_delay", "0.05", "s, first-order lag of the realised ZMP (Kajita: 0.04-0.055)"),
            ("lipm_poles", "[2.5, 4.0, 12.0]", "1/s, closed-loop decay rates of the LIPM law"),
            ("dcm_kp", "4.0", "1/s (HRP-2Kai in mc_rtc: 4)"),
            ("dcm_ki", "15.0", "1/s^2 (HRP-2Kai in mc_rtc: 15)"),
            ("dcm_integral_time", "10.0", "s, leak of the DCM integral"),
            ("cop_margin", "0.005", "m, desired CoPs stay this far inside the sole"),
            ("min_ds_force", "15.0", "N, least normal force per foot in double support"),
            # 240, not 60: with 60 the simulated robot's stance moments carried a 20-30 Hz limit
            # cycle of 3 N m RMS on the default plan, gone at 120 and above (docs/runtime.md).
            ("damping_roll", "240.0", "N m s/rad, foot damping D (sole x moment)"),
            ("damping_pitch", "240.0", "N m s/rad, foot damping D (sole y moment)"),
            ("damping_time_constant", "1.0", "s, return of the foot rotation to the reference"),
            ("max_foot_rotation", "0.17", "rad (10 deg, Kajita 2010)"),
            ("max_foot_rotation_rate", "0.5", "rad/s"),
            # With the bushings' vertical give (bushing_vertical, below) a foot height difference
            # of 1 mm moves ~240 N between the feet, and the loop's rate is K k = 24 1/s at 1e-4.
            # Off, the robot rocked from foot to foot on the springs (~1.7 Hz; CoP p95 33-55 mm,
            # pelvis 10-17 mrad); 2e-5 / 5e-5 / 1e-4 / 2e-4 gave 1-2 / 0-1 / 0-1 / 0-1 losses
            # per run (docs/runtime.md). (On the rigid foot any gain rocked the robot.)
            ("force_difference_gain", "1.0e-4", "m/(N s), foot force difference control"),
            ("max_foot_height", "0.02", "m"),
            # Landing: with the whole-body ZMP reference the soles meet the ground within
            # 0.2 mm of the plan's (6-66 ms late); a fast search (F_d / 4000 N s/m, ~18 mm/s)
            # drove them in and they rebounded (16 contact losses on both plans x 3 seeds),
            # a slow one (F_d / 32000, ~2 mm/s) lands them gently: 4 losses, every CoP maximum
            # within 30 mm (docs/runtime.md).
            ("landing_damping", "32000.0", "N s/m, landing control D (0 = off)"),
            ("landing_time", "0.5", "s after a planned touchdown"),
            ("landing_search_depth", "0.015", "m, deepest a late foot is lowered"),
            ("posture_gain", "0.5", "1/s, body posture from the IMU"),
            ("posture_time_constant", "1.5", "s"),
            ("max_body_attitude", "0.1", "rad"),
            ("com_admittance", "0.0", "1/s^2, 0 = off"),
            ("max_com_offset", "0.05", "m"),
            ("ramp_time", "1.0", "s, ramp-in / ramp-out"),
            ("max_com_error", "0.10", "m, larger -> fault and hold"),
            ("max_torso_tilt", "0.5", "rad, larger -> fault and hold")):
        y.append("  %-24s # %s" % ("%s: %s" % (key, val), comment))
    # Last, and its comments after its key: the section is left out of the robot's hash (the
    # planner's model does not have it), and so is every line up to the next top-level key.
    y.append("")
    y.append("bushing_vertical: {stiffness: 239018, damping: 1000}")
    y.append("# The ankle bushings' vertical give along the sole normal (N/m, N s/m): the LAAS")
    y.append("# identification of the bushing's 6-D stiffness gives z 239018 N/m [open: sot-torque-control];")
    y.append("# estimators use 40000-150000 [open]. Damping [est]: about a tenth of critical with the robot")
    y.append("# on one foot (2 sqrt(k m) ~ 7500 N s/m). The seed's model and the planner's leave it out;")
    y.append("# the simulator has it, and the runtime lengthens each leg in contact by its planned load / stiffness.")
    return "\n".join(y) + "\n"

def main():
    os.makedirs(OUT, exist_ok=True)
    for name, text in (("hrp2.urdf", urdf()), ("hrp2.yaml", yaml())):
        path = os.path.join(OUT, name)
        tmp = path + ".tmp"
        with open(tmp, "w") as fh:
            fh.write(text)
        os.replace(tmp, path)
    total = sum(l["mass"] for l in links.values())
    print("wrote %s/hrp2.urdf and hrp2.yaml: %d links, %d actuated + %d elastic joints, mass %.2f kg"
          % (OUT, len(links), len(joints), len(elastic), total))

if __name__ == "__main__":
    sys.exit(main())

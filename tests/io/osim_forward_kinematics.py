# An independent reading of an .osim file written by s2kf: OpenSim 4's CustomJoint semantics
# (parent offset frame, body-fixed rotations rotation1-3 about their axes, translations along the
# parent's axes, child offset frame) and PhysicalOffsetFrame orientations (body-fixed X-Y-Z Euler),
# in plain Python. Usage: osim_forward_kinematics.py MODEL.osim POSES.txt
# POSES.txt: one pose per line, "name=value" pairs (coordinates in OpenSim units: m, rad).
# Prints "pose marker x y z" (ground frame, m) for every marker of the MarkerSet.
import math
import sys
import xml.etree.ElementTree as ET


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def apply(r, v):
    return [sum(r[i][k] * v[k] for k in range(3)) for i in range(3)]


def axis_angle(axis, angle):
    n = math.sqrt(sum(c * c for c in axis))
    x, y, z = (c / n for c in axis)
    c, s, t = math.cos(angle), math.sin(angle), 1 - math.cos(angle)
    return [[t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c]]


def vec(text):
    return [float(v) for v in text.split()]


def compose(a, b):  # (R, p) transforms: a then b expressed in a
    return (matmul(a[0], b[0]), [a[1][i] + apply(a[0], b[1])[i] for i in range(3)])


def inverse(t):
    rt = [[t[0][j][i] for j in range(3)] for i in range(3)]
    return (rt, [-v for v in apply(rt, t[1])])


def offset_frame(frame):
    angles = vec(frame.find('orientation').text)
    r = matmul(matmul(axis_angle([1, 0, 0], angles[0]), axis_angle([0, 1, 0], angles[1])),
               axis_angle([0, 0, 1], angles[2]))
    return frame.find('socket_parent').text.split('/')[-1], (r, vec(frame.find('translation').text))


def axis_value(axis, q):
    coordinate = (axis.find('coordinates').text or '').strip()
    linear = axis.find('LinearFunction')
    if linear is not None:
        a, b = vec(linear.find('coefficients').text)
        return a * q[coordinate] + b
    return float(axis.find('Constant').find('value').text)


def body_transforms(model, q):
    known = {'ground': ([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [0, 0, 0])}
    joints = list(model.find('JointSet').find('objects'))
    while joints:
        for joint in list(joints):
            frames = {f.get('name'): offset_frame(f) for f in joint.find('frames')}
            parent_body, parent_offset = frames[joint.find('socket_parent_frame').text]
            child_body, child_offset = frames[joint.find('socket_child_frame').text]
            if parent_body not in known:
                continue
            transform = ([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [0, 0, 0])
            axes = {a.get('name'): a for a in joint.find('SpatialTransform')}
            for k in (1, 2, 3):
                a = axes['rotation%d' % k]
                transform = (matmul(transform[0], axis_angle(vec(a.find('axis').text), axis_value(a, q))),
                             transform[1])
            for k in (1, 2, 3):
                a = axes['translation%d' % k]
                transform[1][:] = [transform[1][i] + vec(a.find('axis').text)[i] * axis_value(a, q)
                                   for i in range(3)]
            known[child_body] = compose(compose(compose(known[parent_body], parent_offset), transform),
                                        inverse(child_offset))
            joints.remove(joint)
    return known


model = ET.parse(sys.argv[1]).getroot().find('Model')
for number, line in enumerate(open(sys.argv[2])):
    q = {k: float(v) for k, v in (item.split('=') for item in line.split())}
    bodies = body_transforms(model, q)
    for marker in model.find('MarkerSet').find('objects'):
        body = marker.find('socket_parent_frame').text.split('/')[-1]
        r, p = bodies[body]
        world = [p[i] + apply(r, vec(marker.find('location').text))[i] for i in range(3)]
        print(number, marker.get('name'), *('%.12g' % v for v in world))

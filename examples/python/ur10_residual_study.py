"""What the UR10's residual is not: the checks behind docs/ur10-study.md on the IPA data.

1. Harmonics of one joint's output angle: each order is fitted alone on Series A's first session (the rows
   before the first pause of more than an hour) and scored on that session, on A's later sessions and on
   Series B (each campaign in its own instrument frame, B's frame re-fitted).
2. Series B from Series A's residual field: how far B's poses lie from A's in joint space, and what the mean
   residual of the nearest A poses (rotated into B's frame) does to B.
3. The T-Mac's orientations (optional, from the raw IPA file): what a full kinematic orientation model leaves,
   how repeatable it is, and how much of it the configurations reaching one T-Mac pose share.
4. The tracker's own errors: the residual along the line of sight (distance) and across it (angles), and
   what a smooth function of the direction from the tracker (harmonics of azimuth and elevation, the form
   of a tracker's encoder and axis errors) takes of it. The campaigns' frame is the tracker's own, origin at
   the tracker head, as in the IPA files.
5. Two more physical effects of the whole arm: the bearings' runout (each joint's rotating part tilted about
   the two axes across its own, by harmonics of the joint's angle) and the links' thermal expansion with the
   measured air temperature; each fitted on A with A's frame and scored on B with B's frame re-fitted.
6. Series B's goals, each reached in two configurations (elbow up and down) back to back: how much of the
   residual the two share, what constant joint errors would share, and what smooth functions of the tool
   position or of joint 1's angle, fitted on B itself, leave of it (optional, needs --raw-b).
7. The position residual against the T-Mac's own orientation residual (what a kinematic orientation model fitted
   on A leaves of the measured orientations): coupled as by a fixed lever in the T-Mac's frame, fitted on A and
   applied to B with B's measured orientations (optional, needs --raw-b and --raw-a).

Usage, after `jointcomp import-ipa` of both series and
`jointcomp calibrate --urdf model/robots/ur10.urdf --campaign A.csv --holdout B.csv --out DIR`:
    /usr/bin/python3 examples/python/ur10_residual_study.py DIR A.csv B.csv \
        [--raw-b .../Series_B/measurements_joint_configurations.csv --trafo-b .../Series_B/Trafo_TM_F_init.txt
         [--raw-a .../Series_A/measurements_grid.csv --trafo-a .../Series_A/Trafo_TM_F_init.txt]]

Kinematics: the UR10's published standard DH (data README), with the calibrated target's 93 mm; the
Jacobians only need to be right to a few per cent, so the nominal kinematics serve.
"""

import argparse
import sys

import numpy as np

D = [0.1273, 0.0, 0.0, 0.163941, 0.1157, 0.0922]
A = [0.0, -0.612, -0.5723, 0.0, 0.0, 0.0]
ALPHA = [np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0]
TOOL = np.array([0.0, 0.0, 0.0931])


def read_campaign(path):
    rows = [line.strip().split(",") for line in open(path) if not line.startswith("#")]
    header, values = rows[0], np.array(rows[1:], dtype=float)
    q = np.radians(values[:, [header.index("q%d" % j) for j in range(1, 7)]])
    measured = values[:, [header.index(axis) for axis in ("x", "y", "z")]]
    return q, measured, values[:, header.index("t")]


def read_residuals(path, campaign):
    rows = [line.strip().split(",") for line in open(path)]
    header = rows[0]
    name, columns = header.index("campaign"), [header.index(c) for c in ("dx_mm", "dy_mm", "dz_mm")]
    return np.array([[float(r[c]) for c in columns] for r in rows[1:] if r[name] == campaign])


def frames(q):
    """Per row, the rotation of each DH frame 0..6 and the tool point (m), standard DH."""
    n = len(q)
    rotation = np.tile(np.eye(3), (n, 1, 1))
    position = np.zeros((n, 3))
    rotations, origins = [], []
    for k in range(6):
        rotations.append(rotation.copy())
        origins.append(position.copy())
        c, s = np.cos(q[:, k]), np.sin(q[:, k])
        ca, sa = np.cos(ALPHA[k]), np.sin(ALPHA[k])
        step = np.zeros((n, 3, 3))
        step[:, 0, 0], step[:, 0, 1], step[:, 0, 2] = c, -s * ca, s * sa
        step[:, 1, 0], step[:, 1, 1], step[:, 1, 2] = s, c * ca, -c * sa
        step[:, 2, 1], step[:, 2, 2] = sa, ca
        position = position + np.einsum("nij,nj->ni", rotation, np.stack([A[k] * c, A[k] * s, np.full(n, D[k])], 1))
        rotation = np.einsum("nij,njk->nik", rotation, step)
    rotations.append(rotation)
    tool = position + rotation @ TOOL
    return rotations, origins, tool


def instrument_jacobians(q, measured):
    """d(point)/dq per row (mm/rad) in the campaign's instrument frame (rotation by a rigid fit)."""
    rotations, origins, tool = frames(q)
    points = tool * 1e3
    h = (points - points.mean(0)).T @ (measured - measured.mean(0))
    u, _, vt = np.linalg.svd(h)
    fix = np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T))])
    base_to_instrument = vt.T @ fix @ u.T
    columns = [np.cross(rotations[k][:, :, 2], tool - origins[k]) * 1e3 for k in range(6)]
    return np.einsum("ij,nkj->nik", base_to_instrument, np.stack(columns, 1)), base_to_instrument


def frame_columns(measured):
    """The six frame parameters' columns (translation, small rotation about the centroid), rows x 3 x 6."""
    n = len(measured)
    columns = np.zeros((n, 3, 6))
    centred = measured - measured.mean(0)
    for i in range(3):
        columns[:, i, i] = 1.0
        unit = np.zeros(3)
        unit[i] = 1.0
        columns[:, :, 3 + i] = np.cross(unit, centred)
    return columns


def without_frame(residual, measured):
    """The residual after re-fitting the six frame parameters (linearised)."""
    f = frame_columns(measured).reshape(-1, 6)
    y = residual.reshape(-1)
    return (y - f @ np.linalg.lstsq(f, y, rcond=None)[0]).reshape(-1, 3)


def rms(e):
    return np.sqrt(np.mean(np.sum(e ** 2, axis=1)))


def harmonic_columns(jacobian, q, joint, order):
    column = jacobian[:, :, joint]
    return np.stack([(column * np.sin(order * q[:, joint])[:, None]).reshape(-1),
                     (column * np.cos(order * q[:, joint])[:, None]).reshape(-1)], 1)


def gain(residual, columns, coefficients):
    y = residual.reshape(-1)
    return 1.0 - np.sum((y - columns @ coefficients) ** 2) / np.sum(y ** 2)


def harmonics(a, b, max_order):
    qa, ma, ta, ra = a
    qb, mb, _, rb = b
    ja, _ = instrument_jacobians(qa, ma)
    jb, _ = instrument_jacobians(qb, mb)
    pauses = np.where(np.diff(ta) > 3600.0)[0]
    first = slice(0, pauses[0] + 1 if len(pauses) else len(qa))
    later = slice(first.stop, len(qa))
    results = []
    for joint in range(5):  # joint 6 barely moves a point on its axis
        for order in range(1, max_order + 1):
            columns = harmonic_columns(ja[first], qa[first], joint, order)
            coefficients = np.linalg.lstsq(columns, ra[first].reshape(-1), rcond=None)[0]
            later_gain = gain(ra[later], harmonic_columns(ja[later], qa[later], joint, order), coefficients)
            b_gain = gain(rb, harmonic_columns(jb, qb, joint, order), coefficients)
            results.append((gain(ra[first], columns, coefficients), joint + 1, order, later_gain, b_gain,
                            1e3 * np.hypot(*coefficients)))
    results.sort(reverse=True)
    print("1. output-angle harmonics, orders 1..%d, fitted on A's first session (%d rows):" % (max_order, first.stop))
    for first_gain, joint, order, later_gain, b_gain, amplitude in results[:5]:
        print("   joint %d order %2d (%.3f mrad): first session %+5.1f %%, later sessions %+5.1f %%, B %+5.1f %%"
              % (joint, order, amplitude, 100 * first_gain, 100 * later_gain, 100 * b_gain))
    print("   best on B of all: %+.1f %%" % (100 * max(r[4] for r in results)))


def nearest_from_a(a, b, neighbours):
    qa, ma, _, ra = a
    qb, mb, _, rb = b
    _, a_rotation = instrument_jacobians(qa, ma)
    _, b_rotation = instrument_jacobians(qb, mb)
    distance = np.empty((len(qb), neighbours))
    index = np.empty((len(qb), neighbours), dtype=int)
    squared_a = np.sum(qa ** 2, axis=1)
    for start in range(0, len(qb), 256):
        block = slice(start, min(start + 256, len(qb)))
        d2 = np.sum(qb[block] ** 2, axis=1)[:, None] + squared_a[None, :] - 2 * qb[block] @ qa.T
        nearest = np.argpartition(d2, neighbours, axis=1)[:, :neighbours]
        index[block] = nearest
        distance[block] = np.sqrt(np.maximum(np.take_along_axis(d2, nearest, axis=1), 0.0))
    # A's residuals into the base frame, then into B's instrument frame.
    predicted = (ra @ a_rotation)[index].mean(axis=1) @ b_rotation.T
    print("2. Series B's poses lie %.3f rad (median) from the nearest Series A pose; B's RMS %.4f mm, after "
          "subtracting the mean of its %d nearest A residuals (frame re-fitted): %.4f mm"
          % (np.median(distance[:, 0]), rms(rb), neighbours, rms(without_frame(rb - predicted, mb))))


def euler_xyz(degrees):
    """Intrinsic X-Y-Z Euler angles (deg) to rotation matrices: Rx(a) Ry(b) Rz(c)."""
    a, b, c = np.radians(degrees).T
    ones, zeros = np.ones_like(a), np.zeros_like(a)
    rx = np.stack([ones, zeros, zeros, zeros, np.cos(a), -np.sin(a), zeros, np.sin(a), np.cos(a)], 1).reshape(-1, 3, 3)
    ry = np.stack([np.cos(b), zeros, np.sin(b), zeros, ones, zeros, -np.sin(b), zeros, np.cos(b)], 1).reshape(-1, 3, 3)
    rz = np.stack([np.cos(c), -np.sin(c), zeros, np.sin(c), np.cos(c), zeros, zeros, zeros, ones], 1).reshape(-1, 3, 3)
    return rx @ ry @ rz


def exp_rotation(v):
    angle = np.linalg.norm(v)
    if angle < 1e-15:
        return np.eye(3)
    k = v / angle
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


def log_rotations(r):
    """Rotation vectors of small rotations (n x 3 x 3 -> n x 3)."""
    angle = np.arccos(np.clip((np.trace(r, axis1=1, axis2=2) - 1) / 2, -1.0, 1.0))
    scale = np.where(angle > 1e-12, angle / (2 * np.sin(np.maximum(angle, 1e-12))), 0.5)
    return scale[:, None] * np.stack([r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]], 1)


def project_rotation(m):
    u, _, vt = np.linalg.svd(m)
    return u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))]) @ vt


def read_raw_ipa(raw_path):
    """An IPA file as it is: its header and its values (decimal commas read, empty cells NaN)."""
    rows = [line.strip().split(";") for line in open(raw_path, encoding="latin-1")]
    return rows[0], np.array([[float(c.replace(",", ".")) if c else np.nan for c in r] for r in rows[1:]])


def fit_instrument_rotation(measured, flange, tool, instrument, fit_tool):
    """Gauss-Newton on the instrument's rotation (and the T-Mac's on the flange when fit_tool), by finite
    differences; the residual is the base-frame rotation vector of measured against predicted."""
    def residual(instrument, tool):
        return log_rotations(np.einsum("ij,njk,kl,nml->nim", instrument.T, measured, tool.T, flange))
    count = 6 if fit_tool else 3
    for _ in range(20):
        r0 = residual(instrument, tool).reshape(-1)
        jac = np.empty((len(r0), count))
        for p in range(count):
            step = np.zeros(3)
            step[p % 3] = 1e-7
            trial = (exp_rotation(step) @ instrument, tool) if p < 3 else (instrument, exp_rotation(step) @ tool)
            jac[:, p] = (residual(*trial).reshape(-1) - r0) / 1e-7
        delta = -np.linalg.lstsq(jac, r0, rcond=None)[0]
        instrument = exp_rotation(delta[:3]) @ instrument
        if fit_tool:
            tool = exp_rotation(delta[3:]) @ tool
    return instrument, tool, residual(instrument, tool)


def raw_joints_and_orientations(raw_path):
    """The joint angles and the T-Mac's measured rotations (intrinsic XYZ, deg) of every row of a raw IPA file."""
    header, values = read_raw_ipa(raw_path)
    joints = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
              "wrist_3_joint"]
    q = values[:, [header.index(j) for j in joints]]
    euler = values[:, [header.index("measurement_r" + a) for a in "xyz"]]
    return q, euler


def instrument_and_tool(measured, flange, trafo_path):
    """The instrument's rotation and the T-Mac's on the flange, fitted to the measured rotations from the trafo
    file's rotation taken either way round (the file's direction is not documented): the better fit."""
    trafo = np.loadtxt(trafo_path)[:3, :3]
    best = None
    for tool in (trafo, trafo.T):
        start = project_rotation(np.einsum("nij,kj,nlk->il", measured, tool, flange))
        fit = fit_instrument_rotation(measured, flange, tool, start, True)
        if best is None or rms(fit[2]) < rms(best[2]):
            best = fit
    return best


def kinematic_orientation_columns(rotations):
    """Every small rotation of every joint frame (offsets and placement rotations), base frame, then the
    instrument's (a constant rotation): rows x 3 x 24."""
    joint_frames = np.stack([rotations[k][:, :, axis] for k in range(7) for axis in range(3)], 2)
    return np.concatenate([joint_frames, np.tile(np.eye(3), (len(joint_frames), 1, 1))], 2)


def orientations(raw_path, trafo_path):
    q, euler = raw_joints_and_orientations(raw_path)
    keep = np.isfinite(q).all(1) & np.isfinite(euler).all(1)
    q, measured = q[keep], euler_xyz(euler[keep])
    rotations, _, _ = frames(q)
    best = instrument_and_tool(measured, rotations[6], trafo_path)[2]
    design = kinematic_orientation_columns(rotations).reshape(-1, 24)
    y = best.reshape(-1)
    left = (y - design @ np.linalg.lstsq(design, y, rcond=None)[0]).reshape(-1, 3)
    same_q = np.array([(i, j) for i in range(len(q)) for j in range(i + 1, min(i + 20, len(q)))
                       if np.max(np.abs(q[i] - q[j])) < 1e-4])
    repeat = np.median(np.linalg.norm(left[same_q[:, 0]] - left[same_q[:, 1]], axis=1)) if len(same_q) else np.nan
    print("3. T-Mac orientations of Series B: %.3f mrad after frame and tool rotations, %.3f mrad after every "
          "small rotation of every joint frame; poses measured twice with one joint vector agree to %.3f mrad "
          "(median, %d pairs)" % (1e3 * rms(best), 1e3 * rms(left), 1e3 * repeat, len(same_q)))


def campaign_orientations(raw_path, rows):
    """raw_joints_and_orientations for a campaign imported with every row: each row must have both."""
    q, euler = raw_joints_and_orientations(raw_path)
    if len(q) != rows or not (np.isfinite(q).all() and np.isfinite(euler).all()):
        sys.exit("%s: %d rows (the campaign has %d), every one with its joint angles and orientation expected"
                 % (raw_path, len(q), rows))
    return q, euler_xyz(euler)


def orientation_coupling(raw_a, trafo_a, raw_b, a, b):
    """Check 7: the position residual against the T-Mac's own orientation residual (what a full kinematic
    orientation model fitted on A leaves), coupled as by a fixed lever in the T-Mac's frame: a rotation error
    d of the T-Mac moves its reported point by d x (R l). The lever is fitted on A (with A's frame) and applied
    to B with B's measured orientations (B's frame and instrument rotation re-fitted)."""
    qa, ma = campaign_orientations(raw_a, len(a[0]))
    qb, mb = campaign_orientations(raw_b, len(b[0]))
    rotations_a, _, _ = frames(qa)
    rotations_b, _, _ = frames(qb)
    instrument_a, tool, error_a = instrument_and_tool(ma, rotations_a[6], trafo_a)
    design_a = kinematic_orientation_columns(rotations_a)
    model = np.linalg.lstsq(design_a.reshape(-1, 24), error_a.reshape(-1), rcond=None)[0]
    left_a = error_a - (design_a.reshape(-1, 24) @ model).reshape(-1, 3)
    start = project_rotation(np.einsum("nij,kj,nlk->il", mb, tool, rotations_b[6]))
    instrument_b, _, error_b = fit_instrument_rotation(mb, rotations_b[6], tool, start, False)
    left_b = error_b - (kinematic_orientation_columns(rotations_b)[:, :, :21].reshape(-1, 21) @ model[:21]).reshape(-1, 3)
    left_b -= left_b.mean(0)  # B's own constant rotation, as its frame
    tracker_a, tracker_b = left_a @ instrument_a.T, left_b @ instrument_b.T  # into each instrument's frame

    def lever_columns(error, measured):  # d x (R e_k) for the lever's three components in the T-Mac frame
        return np.stack([np.cross(error, measured[:, :, k]) for k in range(3)], 2)

    ra, rb = a[3], b[3]
    columns = np.concatenate([lever_columns(tracker_a, ma), frame_columns(a[1])], 2).reshape(-1, 9)
    fit = np.linalg.lstsq(columns, ra.reshape(-1), rcond=None)[0]
    a_after = rms((ra.reshape(-1) - columns @ fit).reshape(-1, 3))
    b_after = rms(without_frame(rb - (lever_columns(tracker_b, mb).reshape(-1, 3) @ fit[:3]).reshape(-1, 3), b[1]))
    own = np.concatenate([lever_columns(tracker_b, mb), frame_columns(b[1])], 2).reshape(-1, 9)
    fit_b = np.linalg.lstsq(own, rb.reshape(-1), rcond=None)[0]
    b_own = rms((rb.reshape(-1) - own @ fit_b).reshape(-1, 3))
    print("7. The T-Mac's orientation residual after A's kinematic orientation model: A %.3f mrad, B %.3f mrad; "
          "as a lever in the T-Mac's frame (%.0f, %.0f, %.0f mm, fitted on A) it takes A from %.3f to %.3f mm and, "
          "with B's measured orientations, B from %.3f to %.3f mm (a lever fitted on B itself, (%.0f, %.0f, %.0f) "
          "mm: %.3f mm)" % (1e3 * rms(left_a), 1e3 * rms(left_b), *fit[:3], rms(ra), a_after,
                            rms(without_frame(rb, b[1])), b_after, *fit_b[:3], b_own))


def goal_groups(raw_path, rows):
    """Series B's rows grouped by their goal (the commanded T-Mac pose), from the raw IPA file."""
    header, values = read_raw_ipa(raw_path)
    goals = values[:, [header.index(c) for c in ("Goal x", "Goal y", "Goal z", "Goal roll", "Goal pitch", "Goal yaw")]]
    if len(goals) != rows:
        sys.exit("%s: %d rows, but the campaign has %d (the importer keeps every row)" % (raw_path, len(goals), rows))
    groups = {}
    for i, goal in enumerate(np.round(goals, 5)):
        groups.setdefault(tuple(goal), []).append(i)
    return [np.array(v) for v in groups.values() if len(v) >= 2]


def within_goal_share(residual, groups):
    rows = np.concatenate(groups)
    return sum(np.sum((residual[v] - residual[v].mean(0)) ** 2) for v in groups) / np.sum(residual[rows] ** 2)


def configurations(raw_path, b):
    """Check 6: how much of B's residual the configurations reaching one goal share."""
    qb, mb, _, rb = b
    groups = goal_groups(raw_path, len(qb))
    rows = np.concatenate(groups)
    differences = np.degrees(np.median([np.abs(qb[v[1]] - qb[v[0]]) for v in groups], axis=0))
    jb, b_rotation = instrument_jacobians(qb, mb)
    # What an angle error of joint 2, 3 or 4 alone would leave shared (frame re-fitted, as for the residual).
    joint_shares = [1.0 - within_goal_share(without_frame(jb[:, :, j] * 1e-3, mb), groups) for j in (1, 2, 3)]
    shared = np.zeros_like(rb)
    for v in groups:
        shared[v] = rb[v].mean(0)
    _, _, tool = frames(qb)
    residual_base = rb @ b_rotation

    def left_in_b(columns):  # B's RMS after a least-squares fit of these base-frame columns on B itself
        k = columns.shape[2]
        c = np.linalg.lstsq(columns.reshape(-1, k), residual_base.reshape(-1), rcond=None)[0]
        return rms(without_frame((residual_base - columns @ c) @ b_rotation.T, mb))

    centred = tool - tool.mean(0)
    monomials = [np.ones(len(tool))]
    for degree in range(1, 5):
        for powers in sorted({tuple(sorted(p)) for p in np.ndindex(*(3,) * degree)}):
            monomials.append(np.prod(centred[:, list(powers)], axis=1))
    position_field = np.stack([np.einsum("n,ij->nij", m, np.eye(3)) for m in monomials], 3).reshape(len(tool), 3, -1)
    joint_1 = []  # small rotations about the base axes (joint 1's angle and the tilts across it), harmonics of q1
    for axis in np.eye(3):
        lever = np.cross(axis, tool) * 1e3
        for order in range(9):
            for f in ((np.cos,) if order == 0 else (np.cos, np.sin)):
                joint_1.append(lever * f(order * qb[:, 0])[:, None])
    joint_1 = np.stack(joint_1, 2)
    # A constant angle error of joint 2 or 4 moves the goal's point alike in both elbow configurations (their
    # axes and the wrist are where the goal and joint 1 put them); only joint 3's elbow differs.
    print("6. Series B's configurations of one goal (%d goals, each in 2 or more configurations measured back to back, "
          "differing in joints 2, 3 and 4 by %.0f, %.0f and %.0f deg median): they share %.1f %% of the residual's "
          "squares, where a constant angle error of joint 2, 3 or 4 would share %.0f, %.0f and %.0f %%; the shared part "
          "is %.4f mm RMS, the part that differs %.4f mm; fitted on B itself, a smooth field of the tool position "
          "(degree 4, %d parameters) leaves %.4f mm and harmonics of joint 1 with the base's tilts (orders 0-8, %d "
          "parameters) %.4f mm of B's %.4f mm"
          % (len(groups), differences[1], differences[2], differences[3], 100 * (1 - within_goal_share(rb, groups)),
             *(100 * s for s in joint_shares), rms(shared[rows]), rms((rb - shared)[rows]),
             position_field.shape[2], left_in_b(position_field), joint_1.shape[2], left_in_b(joint_1), rms(rb)))


def tracker_direction_columns(measured, order):
    """Per row 3 x k columns: errors across the beam that grow with range (angle errors) and along it,
    each a harmonic of the azimuth or elevation up to `order`."""
    r = np.linalg.norm(measured, axis=1)
    along = measured / r[:, None]
    azimuth = np.arctan2(measured[:, 1], measured[:, 0])
    elevation = np.arcsin(measured[:, 2] / r)
    across_azimuth = np.stack([-np.sin(azimuth), np.cos(azimuth), np.zeros_like(azimuth)], 1)
    across_elevation = np.cross(along, across_azimuth)
    shapes = [np.ones_like(r)]
    for k in range(1, order + 1):
        shapes += [np.sin(k * azimuth), np.cos(k * azimuth), np.sin(k * elevation), np.cos(k * elevation)]
    columns = []
    for shape in shapes:
        for direction, scale in ((across_azimuth, r), (across_elevation, r), (along, np.ones_like(r))):
            columns.append((shape * scale)[:, None] * direction)
    return np.stack(columns, axis=2).reshape(-1, len(columns))


def tracker(a, b, order):
    _, ma, _, ra = a
    _, mb, _, rb = b
    for name, measured, residual in (("A", ma, ra), ("B", mb, rb)):
        along = np.sum(residual * measured, axis=1) / np.linalg.norm(measured, axis=1)
        across = np.sqrt(np.maximum(np.sum(residual ** 2, axis=1) - along ** 2, 0.0))
        print("4. %s: along the line of sight %.4f mm RMS, across it %.4f mm RMS per axis" %
              (name, np.sqrt(np.mean(along ** 2)), np.sqrt(np.mean(across ** 2) / 2)))
    columns = tracker_direction_columns(ma, order)
    coefficients = np.linalg.lstsq(columns, ra.reshape(-1), rcond=None)[0]
    left = (ra.reshape(-1) - columns @ coefficients).reshape(-1, 3)
    print("   a function of the direction from the tracker (orders 1..%d, %d parameters) fitted on A: A %.4f -> "
          "%.4f mm, %.1f %% of its squares" % (order, columns.shape[1], rms(ra), rms(left), 100 * gain(ra, columns,
                                                                                                   coefficients)))


def runout_columns(q, measured, orders, joints):
    """Per row 3 x k columns (mm per rad): joint k's rotating part turned about the two axes across its own
    that turn with it (a bearing's tilt), times cos and sin of each order of the joint's angle."""
    _, base_to_instrument = instrument_jacobians(q, measured)
    rotations, origins, tool = frames(q)
    columns = []
    for k in joints:
        c, s = np.cos(q[:, k]), np.sin(q[:, k])
        across = (rotations[k][:, :, 0] * c[:, None] + rotations[k][:, :, 1] * s[:, None],
                  rotations[k][:, :, 1] * c[:, None] - rotations[k][:, :, 0] * s[:, None])
        for axis in across:
            moved = np.cross(axis, tool - origins[k]) * 1e3 @ base_to_instrument.T
            for order in orders:
                for shape in (np.cos(order * q[:, k]), np.sin(order * q[:, k])):
                    columns.append(moved * shape[:, None])
    return np.stack(columns, axis=2).reshape(-1, len(columns))


def expansion_columns(q, measured, temperature, reference):
    """One column: every point of the arm moves away from the base by alpha (T - T0) times its distance."""
    _, base_to_instrument = instrument_jacobians(q, measured)
    _, _, tool = frames(q)
    return ((tool * 1e3 @ base_to_instrument.T) * (temperature - reference)[:, None]).reshape(-1, 1)


def fitted_on_a_scored_on_b(name, a, b, columns_a, columns_b):
    """Fits the columns and A's frame on A's residual, then scores B after re-fitting B's frame."""
    _, ma, _, ra = a
    _, mb, _, rb = b
    design = np.hstack([columns_a, frame_columns(ma).reshape(-1, 6)])
    coefficients = np.linalg.lstsq(design, ra.reshape(-1), rcond=None)[0]
    left_a = (ra.reshape(-1) - design @ coefficients).reshape(-1, 3)
    left_b = without_frame((rb.reshape(-1) - columns_b @ coefficients[:columns_b.shape[1]]).reshape(-1, 3), mb)
    print("   %s: A %.4f -> %.4f mm, B %.4f -> %.4f mm" % (name, rms(ra), rms(left_a), rms(without_frame(rb, mb)),
                                                        rms(left_b)))
    return coefficients


def whole_arm(a, b, temperatures):
    qa, ma, _, _ = a
    qb, mb, _, _ = b
    print("5. effects of the whole arm, fitted on A, B with its frame re-fitted:")
    orders, joints = (1, 2), range(6)
    fitted_on_a_scored_on_b("bearing runout of every joint, orders 1-2 (%d parameters)" % (4 * len(orders) * 6), a, b,
                            runout_columns(qa, ma, orders, joints), runout_columns(qb, mb, orders, joints))
    for joint in joints:
        fitted_on_a_scored_on_b("bearing runout of joint %d alone" % (joint + 1), a, b,
                                runout_columns(qa, ma, orders, [joint]), runout_columns(qb, mb, orders, [joint]))
    ta, tb = temperatures
    reference = np.mean(ta)
    alpha = fitted_on_a_scored_on_b("thermal expansion (A %.2f-%.2f degC, B %.2f-%.2f degC)" % (
        ta.min(), ta.max(), tb.min(), tb.max()), a, b, expansion_columns(qa, ma, ta, reference),
        expansion_columns(qb, mb, tb, reference))[0]
    print("   expansion coefficient fitted: %.1f ppm/K (aluminium 23)" % (alpha * 1e6))


def read_temperatures(path):
    rows = [line.strip().split(",") for line in open(path) if not line.startswith("#")]
    column = rows[0].index("temp") if "temp" in rows[0] else None
    return None if column is None else np.array([float(r[column]) for r in rows[1:]])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("calibration", help="output folder of jointcomp calibrate (A fitted, B held out)")
    parser.add_argument("series_a", help="Series A campaign (jointcomp import-ipa)")
    parser.add_argument("series_b", help="Series B campaign (jointcomp import-ipa)")
    parser.add_argument("--max-order", type=int, default=60, help="highest harmonic order scanned")
    parser.add_argument("--neighbours", type=int, default=3)
    parser.add_argument("--raw-b", help="Series B's raw IPA file, for the orientation check")
    parser.add_argument("--trafo-b", help="Series B's Trafo_TM_F_init.txt, with --raw-b")
    parser.add_argument("--raw-a", help="Series A's raw IPA file, with --raw-b: the orientation coupling (check 7)")
    parser.add_argument("--trafo-a", help="Series A's Trafo_TM_F_init.txt, with --raw-a")
    arguments = parser.parse_args()
    residuals = "%s/residuals.csv" % arguments.calibration
    a = read_campaign(arguments.series_a) + (read_residuals(residuals, arguments.series_a.split("/")[-1]),)
    b = read_campaign(arguments.series_b) + (read_residuals(residuals, arguments.series_b.split("/")[-1]),)
    for name, series in (("A", a), ("B", b)):
        if len(series[3]) != len(series[0]):
            sys.exit("%s: %d rows, but %d residual rows of it in %s (every row must be used)"
                     % (name, len(series[0]), len(series[3]), residuals))
    harmonics(a, b, arguments.max_order)
    nearest_from_a(a, b, arguments.neighbours)
    if arguments.raw_b:
        if not arguments.trafo_b:
            sys.exit("--raw-b needs --trafo-b")
        orientations(arguments.raw_b, arguments.trafo_b)
        configurations(arguments.raw_b, b)
        if arguments.raw_a:
            if not arguments.trafo_a:
                sys.exit("--raw-a needs --trafo-a")
            orientation_coupling(arguments.raw_a, arguments.trafo_a, arguments.raw_b, a, b)
    tracker(a, b, 3)
    temperatures = (read_temperatures(arguments.series_a), read_temperatures(arguments.series_b))
    if any(t is None for t in temperatures):
        sys.exit("both campaigns need their temperature column (jointcomp import-ipa writes it)")
    whole_arm(a, b, temperatures)


if __name__ == "__main__":
    main()

"""The robot: kinematics, gravity, joint errors, compensation and the paper's spiral experiment."""

import collections
import ctypes

import numpy as np

from . import _native
from ._handle import OwnedHandle, float_array as _array
from .errors import InvalidArgumentError
from .metrics import Metrics

RUN_NAMES = ("without correction", "stiffness correction", "stiffness and kinematic correction")

SpiralPlan = collections.namedtuple("SpiralPlan", "time tool_positions q qd")
SpiralPlan.__doc__ = """The planned spiral: time (m,) in s, tool_positions (m, 3) in m, q and qd (m, n) in rad, rad/s."""

SpiralExperiment = collections.namedtuple("SpiralExperiment", "metrics errors use_plant")
SpiralExperiment.__doc__ = """The paper's three runs: metrics, one Metrics per run (see RUN_NAMES); errors,
measured minus planned tool positions (3, m, 3) in m, or None when not asked for; use_plant, whether the
simulated robot was the flexible-joint plant."""

TrajectoryCompensation = collections.namedtuple("TrajectoryCompensation", "references max_iterations max_correction")
# The dynamic compensation of a trajectory with time: references and their velocities (m, n), the runs of
# the nominal plant the refinement made and the largest link error it left (rad).
DynamicCompensation = collections.namedtuple("DynamicCompensation",
                                             "references reference_velocities runs max_link_error")
TrajectoryCompensation.__doc__ = """Compensated joint references (m, n) in rad, the largest fixed-point
iteration count, and the largest |planned - reference| in rad."""


_FK_CHUNK = 1 << 20  # rows per jc_forward_kinematics_batch call: 128 MB of poses, far inside int32 lengths


def _optional_array(values):
    return None if values is None else _array(values)


def _length(array):
    return 0 if array is None else array.size


def _effects(effects):
    """None (every effect), a comma-separated str, or a sequence of effect type names."""
    if effects is None:
        return None
    if isinstance(effects, str):
        return effects.encode("utf-8")
    return ",".join(effects).encode("utf-8")


def _rows(values, width, name):
    """``values`` as (m, width) float64 rows and whether it was one row (width,): any other shape is an
    error naming the argument, never reinterpreted (a flat (m * width,) array is not m rows)."""
    array = np.ascontiguousarray(values, dtype=np.float64)
    if array.ndim == 1 and array.shape[0] == width:
        return array.reshape(1, width), True
    if array.ndim == 2 and array.shape[1] == width:
        return array, False
    raise InvalidArgumentError(f"{name} has shape {array.shape}; expected ({width},) or (m, {width})")


def _batch(values, width, name, one):
    """Calls ``one(row)`` for every row of ``values`` ((width,) or (m, width)) and stacks the results."""
    rows, single = _rows(values, width, name)
    results = [one(row) for row in rows]
    if single:
        return results[0]
    if results and isinstance(results[0], tuple):
        return tuple(np.array(part) for part in zip(*results))
    return np.array(results) if results else np.empty((0,))


class Robot(OwnedHandle):
    """A robot loaded from a URDF file with its joint-error parameters.

    ``base_link`` and ``tip_link`` choose the chain (default: the URDF's root, and the end of its longest
    moving chain, as ROS-Industrial's tool0 beside fixed side frames).
    ``Robot(urdf_path, parameters_path)`` reads the parameters from a file (see model/io/parameter_file.hpp),
    ``Robot(urdf_path, parameters_json=text)`` from JSON text, and ``Robot(urdf_path)`` loads the robot
    without joint errors (kinematics and dynamics only). Units are SI: rad, m, N m, s. Every method raises
    a :class:`jointcomp.JointcompError` subclass when the library reports an error.

    The handle is released by :meth:`close` (or a ``with`` block, or garbage collection). A Robot may be
    used from several threads; its calls are serialised.
    """

    def __init__(self, urdf_path, parameters_path=None, *, parameters_json=None, base_link=None, tip_link=None):
        self._handle = None
        handle = ctypes.c_void_p()
        if parameters_json is not None and parameters_path is not None:
            raise ValueError("give parameters_path or parameters_json, not both")
        urdf = _native.text(urdf_path, "urdf_path")
        if base_link is not None or tip_link is not None:
            _native.check(_native.lib.jc_robot_load_chain(
                urdf, _native.text(base_link, "base_link"), _native.text(tip_link, "tip_link"),
                _native.text(parameters_path, "parameters_path"), _native.text(parameters_json, "parameters_json"),
                ctypes.byref(handle)))
        elif parameters_json is not None:
            _native.check(_native.lib.jc_robot_load_json(
                urdf, _native.text(parameters_json, "parameters_json"), ctypes.byref(handle)))
        else:
            _native.check(_native.lib.jc_robot_load(
                urdf, _native.text(parameters_path, "parameters_path"), ctypes.byref(handle)))
        self._handle = handle
        self._dof = self._int32(_native.lib.jc_robot_dof)

    @classmethod
    def from_json(cls, urdf_path, parameters_json):
        """The robot with its parameters given as JSON text."""
        return cls(urdf_path, parameters_json=parameters_json)

    @classmethod
    def from_text(cls, urdf_text, parameters_json=None):
        """The robot from URDF text and its parameters as JSON text (None: kinematics and dynamics only):
        no file needed, as on a worker of another machine."""
        handle = ctypes.c_void_p()
        _native.check(_native.lib.jc_robot_load_text(_native.text(urdf_text, "urdf_text"),
                                                     _native.text(parameters_json, "parameters_json"),
                                                     ctypes.byref(handle)))
        return cls._adopt(handle)

    @classmethod
    def _adopt(cls, handle):
        """A Robot owning a handle the library has just made (identification results)."""
        robot = cls.__new__(cls)
        robot._handle = handle
        robot._dof = robot._int32(_native.lib.jc_robot_dof)
        return robot

    def save(self, urdf_path=None, parameters_path=None):
        """Writes the robot's URDF (its geometry, as calibrated) and/or its parameter file, each whole or
        not at all."""
        _native.check(_native.lib.jc_robot_save(self.handle, _native.text(urdf_path, "urdf_path"),
                                                _native.text(parameters_path, "parameters_path")))

    @staticmethod
    def _release(handle):
        return _native.lib.jc_robot_free(handle)

    def __repr__(self):
        if self._handle is None:
            return "<jointcomp.Robot (closed)>"
        return "<jointcomp.Robot %r, %d joints>" % (self.name, self.dof)

    def _int32(self, function):
        value = ctypes.c_int32()
        _native.check(function(self.handle, ctypes.byref(value)))
        return value.value

    def _text(self, function):
        length = ctypes.c_int32()
        _native.check(function(self.handle, None, 0, ctypes.byref(length)))
        buffer = ctypes.create_string_buffer(length.value + 1)
        _native.check(function(self.handle, buffer, len(buffer), ctypes.byref(length)))
        return buffer.value.decode("utf-8")

    def _joints_out(self, function, q):
        q = _array(q)
        out = np.empty(self._dof)
        _native.check(function(self.handle, _native.pointer(q), q.size, _native.pointer(out), out.size))
        return out

    # ---- queries ----

    @property
    def dof(self):
        """Number of joints n."""
        return self._dof

    @property
    def name(self):
        """The URDF's robot name."""
        return self._text(_native.lib.jc_robot_name)

    def joint_limits(self):
        """(lower, upper) joint limits in rad, -inf and +inf for continuous joints."""
        lower, upper = np.empty(self._dof), np.empty(self._dof)
        _native.check(_native.lib.jc_robot_joint_limits(self.handle, _native.pointer(lower), lower.size,
                                                        _native.pointer(upper), upper.size))
        return lower, upper

    @property
    def has_drives(self):
        """True when the parameters describe the drives (a "plant" object), as plants need."""
        return self._int32(_native.lib.jc_robot_has_drives) == 1

    def parameters_json(self):
        """The joint-error parameters (and drives) as parameter-file JSON text."""
        return self._text(_native.lib.jc_robot_parameters_json)

    @property
    def tool_target(self):
        """The measured target (3, m) on the flange where a calibration put it (jc_calibrate, jc_discover, or
        a parameter file's "tool"), or None."""
        target, has = np.zeros(3), ctypes.c_int32(0)
        _native.check(_native.lib.jc_robot_tool_target(self.handle, _native.pointer(target), 3, ctypes.byref(has)))
        return target if has.value else None

    @property
    def base_frame(self):
        """The base's pose in the instrument's frame (4 x 4, measured = pose @ p_base) where a calibration on
        campaigns in an instrument's frame put it (or a parameter file's "base_frame"), or None."""
        pose, has = np.zeros((4, 4)), ctypes.c_int32(0)
        _native.check(_native.lib.jc_robot_base_frame(self.handle, _native.pointer(pose), 16, ctypes.byref(has)))
        return pose if has.value else None

    # ---- conditions ----

    def set_payload(self, mass, com):
        """A payload of ``mass`` kg with its centre of mass ``com`` (3, m, tool frame), used by
        predict_joint_errors and the compensation."""
        com = _array(com)
        _native.check(_native.lib.jc_robot_set_payload(self.handle, float(mass), _native.pointer(com), com.size))

    def set_tool_wrench(self, wrench):
        """The wrench (6: force in N, then moment in N m about the tool point, base frame) that the
        environment applies at the tool, used by predict_joint_errors and the compensation."""
        wrench = _array(wrench)
        _native.check(_native.lib.jc_robot_set_tool_wrench(self.handle, _native.pointer(wrench), wrench.size))

    # ---- kinematics and dynamics ----

    def forward_kinematics(self, q):
        """Tool pose (4 x 4 homogeneous transform, base frame) at joint positions q (n), or the poses
        (m, 4, 4) of a batch q (m, n): one library call per chunk of rows, never a list per row."""
        rows, single = _rows(q, self._dof, "q")
        if single:
            pose = np.empty((4, 4))
            _native.check(_native.lib.jc_forward_kinematics(self.handle, _native.pointer(rows[0]), self._dof,
                                                            _native.pointer(pose), pose.size))
            return pose
        poses = np.empty((rows.shape[0], 4, 4))
        for start in range(0, rows.shape[0], _FK_CHUNK):
            chunk, out = rows[start:start + _FK_CHUNK], poses[start:start + _FK_CHUNK]
            _native.check(_native.lib.jc_forward_kinematics_batch(
                self.handle, chunk.shape[0], _native.pointer(chunk), chunk.size, _native.pointer(out), out.size))
        return poses

    def inverse_kinematics(self, pose, seed):
        """(q, singular): the joint positions reaching ``pose`` (4 x 4) closest to ``seed`` (n), and whether
        they sit at a singularity. Raises UnreachableError when no solution lies within the limits."""
        pose, seed = _array(pose), _array(seed)
        q = np.empty(self._dof)
        singular = ctypes.c_int32()
        _native.check(_native.lib.jc_inverse_kinematics(self.handle, _native.pointer(pose), pose.size,
                                                        _native.pointer(seed), seed.size, _native.pointer(q), q.size,
                                                        ctypes.byref(singular)))
        return q, singular.value == 1

    def inverse_kinematics_all(self, pose, seed):
        """Every closed-form solution within the limits, (k, n) with k <= 8, each close to ``seed``."""
        pose, seed = _array(pose), _array(seed)
        solutions = np.empty((8, self._dof))
        count = ctypes.c_int32()
        _native.check(_native.lib.jc_inverse_kinematics_all(self.handle, _native.pointer(pose), pose.size,
                                                            _native.pointer(seed), seed.size,
                                                            _native.pointer(solutions), solutions.size,
                                                            ctypes.byref(count)))
        return solutions[:count.value].copy()

    def jacobian(self, q):
        """Geometric Jacobian of the tool (6 x n): linear velocity rows first, then angular, base frame; for
        a batch q (m, n), (m, 6, n)."""
        def one(row):
            jacobian = np.empty((6, self._dof))
            _native.check(_native.lib.jc_jacobian(self.handle, _native.pointer(row), row.size,
                                                  _native.pointer(jacobian), jacobian.size))
            return jacobian
        return _batch(q, self._dof, "q", one)

    def gravity_torques(self, q):
        """Joint torques (n, N m) holding the robot still against gravity at q; for a batch (m, n), (m, n)."""
        return _batch(q, self._dof, "q", lambda row: self._joints_out(_native.lib.jc_gravity_torques, row))

    # ---- joint errors and compensation ----

    def predict_joint_errors(self, command, velocity=None, effects=None):
        """Joint errors (n, rad, link minus command) of the quasi-static robot commanded to ``command``
        (n), or (m, n) for a batch of commands (m, n) with optional velocities of the same shape.

        ``effects``: None for every effect of the parameters, or the error effect types taking part
        ("compliance", "transmission_error", as a comma-separated str or a sequence); load effects always do.
        """
        rows, single = _rows(command, self._dof, "command")
        velocities = None if velocity is None else _rows(velocity, self._dof, "velocity")[0]
        if velocities is not None and velocities.shape != rows.shape:
            raise InvalidArgumentError(f"velocity has shape {np.shape(velocity)}; command has {np.shape(command)}")
        out = np.empty(rows.shape)
        for k, row in enumerate(rows):
            v = None if velocities is None else velocities[k]
            _native.check(_native.lib.jc_predict_joint_errors(
                self.handle, _effects(effects), _native.pointer(row), row.size, _native.pointer(v), _length(v),
                _native.pointer(out[k]), self._dof))
        return out[0] if single else out

    def compensate(self, planned, velocity=None, effects=None):
        """(reference, iterations): the joint reference that brings the links to ``planned`` (n), and the
        fixed-point iterations it took; for a batch ``planned`` (m, n), references (m, n) and iterations
        (m,). ``effects`` as for predict_joint_errors."""
        rows, single = _rows(planned, self._dof, "planned")
        velocities = None if velocity is None else _rows(velocity, self._dof, "velocity")[0]
        if velocities is not None and velocities.shape != rows.shape:
            raise InvalidArgumentError(f"velocity has shape {np.shape(velocity)}; planned has {np.shape(planned)}")
        references = np.empty(rows.shape)
        counts = np.empty(rows.shape[0], dtype=np.int32)
        iterations = ctypes.c_int32()
        for k, row in enumerate(rows):
            v = None if velocities is None else velocities[k]
            _native.check(_native.lib.jc_compensate_point(
                self.handle, _effects(effects), _native.pointer(row), row.size, _native.pointer(v), _length(v),
                _native.pointer(references[k]), self._dof, ctypes.byref(iterations)))
            counts[k] = iterations.value
        return (references[0], int(counts[0])) if single else (references, counts)

    def compensate_trajectory(self, planned, velocities=None, effects=None):
        """Compensates a whole trajectory, ``planned`` (m, n) with optional ``velocities`` (m, n), in one
        call. Returns a TrajectoryCompensation."""
        planned = np.ascontiguousarray(planned, dtype=np.float64)
        if planned.ndim != 2 or planned.shape[1] != self._dof:
            raise InvalidArgumentError(f"planned has shape {planned.shape}; expected (m, {self._dof})")
        if velocities is not None and np.shape(velocities) != planned.shape:
            raise InvalidArgumentError(f"velocities has shape {np.shape(velocities)}; expected {planned.shape}")
        shape = planned.shape
        planned, velocities = planned.reshape(-1), _optional_array(velocities)
        references = np.empty(planned.size)
        max_iterations = ctypes.c_int32()
        max_correction = ctypes.c_double()
        _native.check(_native.lib.jc_compensate_trajectory(
            self.handle, _effects(effects), _native.pointer(planned), planned.size, _native.pointer(velocities),
            _length(velocities), _native.pointer(references), references.size, ctypes.byref(max_iterations),
            ctypes.byref(max_correction)))
        return TrajectoryCompensation(references.reshape(shape), max_iterations.value, max_correction.value)

    def compensate_dynamic(self, times, planned, velocities):
        """The dynamic compensation of a trajectory with time: ``times`` (m,), ``planned`` and
        ``velocities`` (m, n). The references make the modelled robot (flexible joints, drives and
        controller, every effect, the payload and tool wrench set on this robot) put its links on the plan
        at any speed; give the plant (or the robot's controller) the references with their velocities.
        Needs the parameters' "plant" object. Returns a DynamicCompensation."""
        times = np.ascontiguousarray(times, dtype=np.float64)
        planned = np.ascontiguousarray(planned, dtype=np.float64)
        velocities = np.ascontiguousarray(velocities, dtype=np.float64)
        if times.ndim != 1:
            raise InvalidArgumentError(f"times has shape {times.shape}; expected (m,)")
        expected = (times.size, self._dof)
        for name, array in (("planned", planned), ("velocities", velocities)):
            if array.shape != expected:
                raise InvalidArgumentError(f"{name} has shape {array.shape}; expected {expected}")
        references = np.empty(expected)
        reference_velocities = np.empty(expected)
        runs = ctypes.c_int32()
        max_link_error = ctypes.c_double()
        _native.check(_native.lib.jc_compensate_trajectory_dynamic(
            self.handle, _native.pointer(times), times.size, _native.pointer(planned), planned.size,
            _native.pointer(velocities), velocities.size, _native.pointer(references), references.size,
            _native.pointer(reference_velocities), reference_velocities.size, ctypes.byref(runs),
            ctypes.byref(max_link_error)))
        return DynamicCompensation(references, reference_velocities, runs.value, max_link_error.value)

    # ---- the paper's spiral ----

    def spiral_sample_count(self):
        """Number of samples m of the paper's planned spiral."""
        return self._int32(_native.lib.jc_spiral_sample_count)

    def spiral_plan(self):
        """The paper's spiral planned for this robot, as a SpiralPlan."""
        m = self.spiral_sample_count()
        time, positions = np.empty(m), np.empty((m, 3))
        q, qd = np.empty((m, self._dof)), np.empty((m, self._dof))
        _native.check(_native.lib.jc_spiral_plan(self.handle, _native.pointer(time), time.size,
                                                 _native.pointer(positions), positions.size, _native.pointer(q),
                                                 q.size, _native.pointer(qd), qd.size))
        return SpiralPlan(time, positions, q, qd)

    def spiral_experiment(self, use_plant=None, errors=False, truth=None):
        """The paper's experiment (three runs, see RUN_NAMES) as a SpiralExperiment.

        ``use_plant``: simulate the robot as the flexible-joint plant (True) or quasi-statically (False);
        None picks the plant when the parameters (of the truth, when given) describe the drives.
        ``errors``: also return the measured-minus-planned tool positions of every run. ``truth``: a Robot
        the simulated robot follows (this robot's parameters compensate; jc_spiral_experiment_truth); None:
        the built-in seeded perturbation of this robot's parameters (jc_spiral_experiment).
        """
        if truth is not None and not isinstance(truth, Robot):
            raise TypeError("truth must be a jointcomp.Robot, not %s" % type(truth).__name__)
        simulated = self if truth is None else truth
        if use_plant is None:
            use_plant = simulated.has_drives
        metrics = np.empty((3, 5))
        error_array = np.empty((3, self.spiral_sample_count(), 3)) if errors else None
        if truth is None:
            _native.check(_native.lib.jc_spiral_experiment(self.handle, 1 if use_plant else 0,
                                                           _native.pointer(metrics), metrics.size,
                                                           _native.pointer(error_array), _length(error_array)))
        else:
            _native.check(_native.lib.jc_spiral_experiment_truth(
                self.handle, truth.handle, 1 if use_plant else 0, _native.pointer(metrics), metrics.size,
                _native.pointer(error_array), _length(error_array)))
        return SpiralExperiment([Metrics(*row) for row in metrics.tolist()], error_array, bool(use_plant))

    def plant(self, **options):
        """A new flexible-joint plant of this robot, with the integrator's options (see jointcomp.Plant)."""
        from .plant import Plant
        return Plant(self, **options)

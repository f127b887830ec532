"""The flexible-joint plant: a simulated robot integrated by CVODE."""

import collections
import ctypes

import numpy as np

from . import _native
from ._handle import OwnedHandle, float_array as _array, options_json

PlantStatistics = collections.namedtuple(
    "PlantStatistics", "steps rhs_evaluations jacobian_evaluations error_test_failures convergence_failures")
PlantStatistics.__doc__ = """CVODE's counts since the plant was created."""


class Plant(OwnedHandle):
    """The robot as a flexible-joint plant: per joint a motor under a PID position controller drives the
    link through the gear train and the joint spring; the links follow the rigid-body dynamics.

    ``Plant(robot)`` needs parameters that describe the drives (``robot.has_drives``); the plant keeps its
    own copy of them. Start it with :meth:`reset`, feed references with :meth:`set_reference`, integrate
    with :meth:`advance`, read the outputs. SI units throughout.

    Keyword options set the integrator and the watchdog (``jc_plant_create_with_options``):
    ``relative_tolerance``, ``absolute_tolerance``, ``max_order``, ``step_past_updates_s``, ``even_steps``, ...;
    e.g. ``Plant(robot, step_past_updates_s=0.01)`` lets CVODE step through 1 ms updates (about twice as
    fast; a reference within ``step_past_tolerance_rad``, 5 urad, of the one CVODE already integrated takes
    effect from CVODE's next step, one that departs further restarts CVODE at its time). An unknown option
    raises.
    """

    def __init__(self, robot, **options):
        self._handle = None
        handle = ctypes.c_void_p()
        if options:
            _native.check(_native.lib.jc_plant_create_with_options(robot.handle, options_json(options),
                                                                   ctypes.byref(handle)))
        else:
            _native.check(_native.lib.jc_plant_create(robot.handle, ctypes.byref(handle)))
        self._handle = handle
        dof = ctypes.c_int32()
        _native.check(_native.lib.jc_plant_dof(self._handle, ctypes.byref(dof)))
        self._dof = dof.value

    @staticmethod
    def _release(handle):
        return _native.lib.jc_plant_free(handle)

    @property
    def dof(self):
        """Number of joints n."""
        return self._dof

    @property
    def time(self):
        """The plant's time, s."""
        time = ctypes.c_double()
        _native.check(_native.lib.jc_plant_time(self.handle, ctypes.byref(time)))
        return time.value

    def reset(self, command, start_time=0.0):
        """Starts at rest in static equilibrium with the motors at ``command`` (n), at ``start_time``."""
        command = _array(command)
        _native.check(_native.lib.jc_plant_reset(self.handle, _native.pointer(command), command.size,
                                                 float(start_time)))

    def set_reference(self, position, velocity):
        """The controller follows ``position`` (n) from now on, extrapolated with ``velocity`` (n) and the
        acceleration seen between the last two updates; a joint given a velocity of exactly 0 stops and holds
        ``position`` until the next update."""
        position, velocity = _array(position), _array(velocity)
        _native.check(_native.lib.jc_plant_set_reference(self.handle, _native.pointer(position), position.size,
                                                         _native.pointer(velocity), velocity.size))

    def set_tool_wrench(self, wrench):
        """Wrench (6: force in N, moment in N m about the tool point, base frame) applied at the tool."""
        wrench = _array(wrench)
        _native.check(_native.lib.jc_plant_set_tool_wrench(self.handle, _native.pointer(wrench), wrench.size))

    def set_payload(self, mass, com):
        """Payload of ``mass`` kg with its centre of mass ``com`` (3, m, tool frame)."""
        com = _array(com)
        _native.check(_native.lib.jc_plant_set_payload(self.handle, float(mass), _native.pointer(com), com.size))

    def advance(self, end_time):
        """Integrates to ``end_time`` (s, after the current time). Raises SolverError when CVODE fails, and
        PlantLimitError when the run ends with a link beyond its joint limits or a drive beyond its
        tracking envelope (see :meth:`set_watchdog`); the plant then refuses to advance until reset."""
        _native.check(_native.lib.jc_plant_advance(self.handle, float(end_time)))

    def set_watchdog(self, tracking_envelope_rad=0.2, joint_limit_margin_rad=0.02):
        """The watchdog's limits: the largest following error |reference - motor position| (rad) and how
        far a link may go beyond its joint limits (rad)."""
        _native.check(_native.lib.jc_plant_set_watchdog(self.handle, float(tracking_envelope_rad),
                                                        float(joint_limit_margin_rad)))

    def _read(self, function, size):
        values = np.empty(size)
        _native.check(function(self.handle, _native.pointer(values), values.size))
        return values

    def link_positions(self):
        """Link positions q (n, rad)."""
        return self._read(_native.lib.jc_plant_link_positions, self._dof)

    def link_velocities(self):
        """Link velocities qd (n, rad/s)."""
        return self._read(_native.lib.jc_plant_link_velocities, self._dof)

    def motor_positions(self):
        """Motor positions p in joint units (n, rad)."""
        return self._read(_native.lib.jc_plant_motor_positions, self._dof)

    def motor_velocities(self):
        """Motor velocities pd in joint units (n, rad/s)."""
        return self._read(_native.lib.jc_plant_motor_velocities, self._dof)

    def motor_torques(self):
        """Motor torques the controller applies now (n, N m, joint units)."""
        return self._read(_native.lib.jc_plant_motor_torques, self._dof)

    def state(self):
        """The integrator's state y = [q, qd, p, pd, integral of the position error] (5 n). Like save(),
        reading it restarts the integrator's step-size history."""
        return self._read(_native.lib.jc_plant_state, 5 * self._dof)

    def statistics(self):
        """CVODE's counts, as PlantStatistics."""
        counts = np.empty(5, dtype=np.int64)
        _native.check(_native.lib.jc_plant_statistics(self.handle, counts.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
                                                      counts.size))
        return PlantStatistics(*(int(c) for c in counts))

    @property
    def snapshot_size(self):
        """Number of doubles in a snapshot."""
        size = ctypes.c_int32()
        _native.check(_native.lib.jc_plant_snapshot_size(self.handle, ctypes.byref(size)))
        return size.value

    def save(self):
        """A snapshot of everything needed to continue exactly from now (a float64 array)."""
        return self._read(_native.lib.jc_plant_save, self.snapshot_size)

    def restore(self, snapshot):
        """Continues from a snapshot taken by save() of a plant of the same robot."""
        snapshot = _array(snapshot)
        _native.check(_native.lib.jc_plant_restore(self.handle, _native.pointer(snapshot), snapshot.size))

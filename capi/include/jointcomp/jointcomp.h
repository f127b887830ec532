/**
 * @file
 * jointcomp C API: joint-error prediction, offline compensation and the flexible-joint plant of serial
 * industrial robots, behind one prefix (jc_) and opaque handles.
 *
 * Conventions (every function follows them):
 * - Units are SI: rad, m, N m, s (and rad/s, N, kg).
 * - Every call that can fail returns a jc_status: JC_OK (0) or a negative JC_ERROR_* code. On failure the
 *   outputs are left untouched and jc_last_error() says what was wrong, naming the function and argument.
 *   Only the version, status-name and last-error queries return their value directly: they cannot fail.
 * - Arrays are double (or int64_t) pointers followed by their length in elements. A length must be
 *   exactly what the function's comment asks for ("n" is the robot's number of joints), except where
 *   the comment says "at least". Matrices are row-major: element (r, c) of an R x C matrix is at
 *   [r * C + c]. Poses are 4 x 4 homogeneous transforms (16 values, row-major).
 * - Inputs must be finite: NaN and infinities are rejected with JC_ERROR_INVALID_ARGUMENT.
 * - Outputs marked "optional" may be NULL with length 0 when not wanted.
 * - Handles (jc_robot, jc_plant, jc_report, jc_spiral_job) are created by jc_*_load / jc_*_create (and the
 *   identification calls) and released by jc_*_free; freeing NULL is a no-op. The rules of their lifetime,
 *   which the library enforces:
 *   1. A handle is busy while a call that was given it runs (on any thread, including the call whose
 *      progress callback is running). jc_*_free of a busy handle returns JC_ERROR_BUSY and frees nothing:
 *      free it after those calls have returned (join your threads first). A progress callback may use the
 *      handles of the call that runs it, but not free them.
 *   2. A pointer is checked against the library's table of live handles before it is read, so a handle of
 *      the wrong kind, one already freed, or a pointer that never was a handle is JC_ERROR_WRONG_HANDLE
 *      (never a crash). Only when a new handle of the same kind was since created at the same address is a
 *      freed handle taken for that new one: so never use a handle after freeing it.
 *   3. A handle freed on one thread while another thread is only about to pass it to a call is the race
 *      of rule 2: synchronise the free with the threads that use the handle.
 * - Threads: every handle may be used from any thread. Calls on one handle are serialised by a lock
 *   inside it; separate handles share nothing mutable, so calls on them run in parallel. The last-error
 *   message is per thread.
 */
#ifndef JOINTCOMP_JOINTCOMP_H
#define JOINTCOMP_JOINTCOMP_H

#include <stdint.h>

/* Only the library's own build marks the API for export; users see plain declarations (which keeps the
   header readable by strict C parsers such as MATLAB's loadlibrary). */
#if defined(JOINTCOMP_BUILDING_LIBRARY) && defined(__GNUC__)
#define JOINTCOMP_API __attribute__((visibility("default")))
#else
#define JOINTCOMP_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/** Version of the binary interface: changes whenever a function's signature or meaning changes
   incompatibly. It is also the shared library's SOVERSION (libjointcomp.so.1 for version 1). */
#define JC_ABI_VERSION 1

/** Status codes. */
typedef int32_t jc_status;
#define JC_OK 0                        /**< success */
#define JC_ERROR_INVALID_ARGUMENT (-1) /**< NULL pointer, wrong length, NaN or infinity, out of range */
#define JC_ERROR_FILE (-2)             /**< unreadable or malformed URDF or parameter file or text */
#define JC_ERROR_UNREACHABLE (-3)      /**< a pose outside the workspace or the joint limits */
#define JC_ERROR_SOLVER (-4)           /**< no convergence, integrator failure */
#define JC_ERROR_WRONG_HANDLE (-5)     /**< a handle of another kind, or one already freed */
#define JC_ERROR_OUT_OF_MEMORY (-6)    /**< the memory a call needed was not there */
#define JC_ERROR_INTERNAL (-7)         /**< a bug: please report it with the message */
#define JC_ERROR_PLANT_LIMIT (-8)      /**< a simulation that left its joint limits or its tracking envelope */
#define JC_ERROR_BUSY (-9)             /**< a *_free of a handle that a call in progress still uses: not freed */

/* Opaque handles. */
typedef struct jc_robot jc_robot;   /**< a robot, its joint-error model and (optionally) its drives */
typedef struct jc_plant jc_plant;   /**< a simulated flexible-joint robot, integrated by CVODE */
typedef struct jc_report jc_report; /**< the report of an identification, a calibration or a discovery */

/** @name Library
    @{ */

/** The library's version, "major.minor.patch". */
JOINTCOMP_API const char* jc_version(void);
/** JC_ABI_VERSION of the library actually loaded (compare it with the header's). */
JOINTCOMP_API int32_t jc_abi_version(void);
/** Message of the last failed call on this thread ("" after a successful call). Valid until the next
   jc_ call on this thread. */
JOINTCOMP_API const char* jc_last_error(void);
/** Progress of long calls (jc_calibrate, jc_discover): `callback` is told, on the calling thread, what they
   are doing ("calibrating: iteration 4, RMS 0.2431 mm per axis"), with `user_data`; NULL: silent (the
   default). Per thread, like jc_last_error. */
typedef void (*jc_progress_callback)(const char* message, void* user_data);
/** Sets this thread's progress callback and its user_data (NULL: silent). */
JOINTCOMP_API jc_status jc_set_progress_callback(jc_progress_callback callback, void* user_data);

/** The name of a status code, e.g. "JC_ERROR_SOLVER" ("JC_UNKNOWN_STATUS" for other values). */
JOINTCOMP_API const char* jc_status_name(jc_status status);

/** @} */

/** @name Robot
    @{ */

/** Loads the robot from a URDF file and its joint-error parameters from a parameter file (JSON, see
   model/io/parameter_file.hpp); parameter_path may be NULL for kinematics and dynamics only (no joint
   errors). The drives and controller gains of the parameter file's "plant" object, when present, are
   kept for jc_plant_create and jc_spiral_experiment. *robot receives the new handle. */
JOINTCOMP_API jc_status jc_robot_load(const char* urdf_path, const char* parameter_path, jc_robot** robot);
/** The same with the parameters given as JSON text instead of a file. */
JOINTCOMP_API jc_status jc_robot_load_json(const char* urdf_path, const char* parameters_json, jc_robot** robot);
/** The chain of the URDF from base_link to tip_link (NULL or "": the URDF's root link, and the end of its
   longest moving chain, as ROS-Industrial's tool0 beside fixed side frames), with the parameters of a
   file or JSON text (at most one of them; neither: kinematics and dynamics only). An ambiguous tree or
   an unknown link is JC_ERROR_FILE naming it. */
JOINTCOMP_API jc_status jc_robot_load_chain(const char* urdf_path, const char* base_link, const char* tip_link,
                                            const char* parameter_path, const char* parameters_json, jc_robot** robot);
/** Releases the robot (NULL: nothing to do); JC_ERROR_BUSY while a call still uses it. */
JOINTCOMP_API jc_status jc_robot_free(jc_robot* robot);

/** Number of joints n. */
JOINTCOMP_API jc_status jc_robot_dof(jc_robot* robot, int32_t* dof);
/** The URDF's robot name, NUL-terminated, into buffer (capacity bytes). *length receives the name's
   length without the NUL. buffer may be NULL with capacity 0 to ask for the length only; a buffer too
   small is an error. */
JOINTCOMP_API jc_status jc_robot_name(jc_robot* robot, char* buffer, int32_t capacity, int32_t* length);
/** Joint limits (n each); -inf and +inf for continuous joints. */
JOINTCOMP_API jc_status jc_robot_joint_limits(jc_robot* robot, double* lower, int32_t lower_len, double* upper,
                                              int32_t upper_len);
/** *has_drives = 1 when the parameters have a "plant" object (needed for plants), else 0. */
JOINTCOMP_API jc_status jc_robot_has_drives(jc_robot* robot, int32_t* has_drives);
/** The joint-error parameters (and drives) as parameter-file JSON; buffer as for jc_robot_name. */
JOINTCOMP_API jc_status jc_robot_parameters_json(jc_robot* robot, char* buffer, int32_t capacity, int32_t* length);

/** Where a calibration put the measured target (robots from jc_calibrate and jc_discover, or loaded with a
   parameter file that has a "tool" object): target (3, m) on the nominal robot's tip link (the flange).
   *has_target = 0 (and zeros written) when the robot carries none. */
JOINTCOMP_API jc_status jc_robot_tool_target(jc_robot* robot, double* target, int32_t target_len, int32_t* has_target);
/** The base's pose in the instrument's frame of a calibration's first campaign (robots from jc_calibrate
   and jc_discover on campaigns in an instrument's frame, or loaded with a parameter file that has a
   "base_frame" object): pose (16, row-major), measured = pose * p_base. *has_base_frame = 0 (and the
   identity written) when the robot carries none: campaigns in the base frame have no base frame. */
JOINTCOMP_API jc_status jc_robot_base_frame(jc_robot* robot, double* pose, int32_t pose_len, int32_t* has_base_frame);

/** Writes the robot's URDF (its geometry, as calibrated when it came from jc_calibrate or jc_discover) and
   its parameter file (joint-error effects and drives), each whole or not at all (temporary file and
   rename). Either path may be NULL to skip that file. The URDF's chain ends where the handle's does (the
   flange); a calibrated robot's URDF has a link fixed to the root at the instrument's frame, and its
   parameter file says where the target and that frame are ("tool", "base_frame"), so that a robot loaded
   from the two files gives the same jc_robot_tool_target and jc_robot_base_frame. */
JOINTCOMP_API jc_status jc_robot_save(jc_robot* robot, const char* urdf_path, const char* parameter_path);

/** Conditions of the robot handle, used by jc_predict_joint_errors and jc_compensate_* (not by the spiral):
   a payload of `mass` kg whose centre of mass is com (3, m, tool frame), and a wrench (6: force in N,
   then moment in N m about the tool point, base frame) that the environment applies at the tool.
   Both are zero after loading. */
JOINTCOMP_API jc_status jc_robot_set_payload(jc_robot* robot, double mass, const double* com, int32_t com_len);
/** The wrench (6) the environment applies at the tool, as for jc_robot_set_payload. */
JOINTCOMP_API jc_status jc_robot_set_tool_wrench(jc_robot* robot, const double* wrench, int32_t wrench_len);

/** @} */

/** @name Kinematics and dynamics
    @{ */

/** Pose of the tool frame in the base frame at joint positions q (n): pose (16). */
JOINTCOMP_API jc_status jc_forward_kinematics(jc_robot* robot, const double* q, int32_t q_len, double* pose,
                                              int32_t pose_len);
/** The joint positions q (n) that put the tool at pose (16, a rigid transform), closest to seed (n).
   *singular (optional, may be NULL) receives 1 at a singularity, where a redundant joint kept its seed
   value. JC_ERROR_UNREACHABLE when no solution lies within the joint limits. */
JOINTCOMP_API jc_status jc_inverse_kinematics(jc_robot* robot, const double* pose, int32_t pose_len, const double* seed,
                                              int32_t seed_len, double* q, int32_t q_len, int32_t* singular);
/** Every closed-form solution (up to 8) within the limits, each as close to seed as the limits allow:
   solutions (at least 8 n) receives *count rows of n. JC_ERROR_INVALID_ARGUMENT for arms without a
   closed form (see model/robot/inverse_kinematics.hpp). */
JOINTCOMP_API jc_status jc_inverse_kinematics_all(jc_robot* robot, const double* pose, int32_t pose_len,
                                                  const double* seed, int32_t seed_len, double* solutions,
                                                  int32_t solutions_len, int32_t* count);
/** Geometric Jacobian of the tool frame at q (n): jacobian (6 x n, row-major), rows 0-2 the tool point's
   linear velocity, rows 3-5 the angular velocity, base frame. */
JOINTCOMP_API jc_status jc_jacobian(jc_robot* robot, const double* q, int32_t q_len, double* jacobian,
                                    int32_t jacobian_len);
/** Joint torques (n) that hold the robot still against gravity at q (n). */
JOINTCOMP_API jc_status jc_gravity_torques(jc_robot* robot, const double* q, int32_t q_len, double* torques,
                                           int32_t torques_len);

/** @} */

/** @name Joint errors and compensation
   `effects` selects the joint-error effects taking part: NULL for every effect of the parameters, or a
   comma-separated list of effect types ("compliance,transmission_error"; "" for none). Load effects
   (spring balancer, payload, wrench) always take part, since the errors depend on the load. The paper's
   three runs are "" (no correction), "compliance" and "compliance,transmission_error".
   @{ */

/** Joint errors (n, link minus command) of the quasi-static robot commanded to `command` (n) moving at
   `velocity` (optional, n; NULL for at rest): the links settle where the selected effects put them.
   JC_ERROR_SOLVER when they do not settle. */
JOINTCOMP_API jc_status jc_predict_joint_errors(jc_robot* robot, const char* effects, const double* command,
                                                int32_t command_len, const double* velocity, int32_t velocity_len,
                                                double* errors, int32_t errors_len);
/** The joint reference (n) that brings the links to `planned` (n) moving at `velocity` (optional, n):
   reference = planned - errors(planned, reference). *iterations (optional) receives the fixed-point
   iterations used. JC_ERROR_SOLVER when the iteration does not converge. */
JOINTCOMP_API jc_status jc_compensate_point(jc_robot* robot, const char* effects, const double* planned,
                                            int32_t planned_len, const double* velocity, int32_t velocity_len,
                                            double* reference, int32_t reference_len, int32_t* iterations);
/** The same for a whole trajectory of m points: planned (m x n), velocities (optional, m x n), references
   (m x n); m is planned_len / n. *max_iterations and *max_correction (optional) receive the largest
   iteration count and the largest |planned - reference| (rad). */
JOINTCOMP_API jc_status jc_compensate_trajectory(jc_robot* robot, const char* effects, const double* planned,
                                                 int32_t planned_len, const double* velocities, int32_t velocities_len,
                                                 double* references, int32_t references_len, int32_t* max_iterations,
                                                 double* max_correction);

/** @} */

/** @name The paper's spiral (Olabi et al., IEEE ICIT 2012)
   The logarithmic spiral R = a exp(b theta), a = 24 mm, b = 0.15, theta 0 to 4 pi, in the plane Z = 200 mm
   centred 1.2 m in front of the robot, the tool pointing down, at 30 mm/s with a jerk-limited feed rate
   sampled every 4 ms (the defaults of model/compensation/spiral_experiment.hpp).
   @{ */

/** Number of samples m of the planned spiral. */
JOINTCOMP_API jc_status jc_spiral_sample_count(jc_robot* robot, int32_t* count);
/** The planned spiral: time (m, s), tool_positions (m x 3), joint positions q (m x n) and velocities qd
   (m x n). Each output is optional. JC_ERROR_UNREACHABLE when the robot cannot reach the spiral. */
JOINTCOMP_API jc_status jc_spiral_plan(jc_robot* robot, double* time, int32_t time_len, double* tool_positions,
                                       int32_t tool_positions_len, double* q, int32_t q_len, double* qd,
                                       int32_t qd_len);
/** The paper's experiment: a simulated robot whose true joint errors differ from the nominal parameters
   follows the spiral three times (0: without correction, 1: stiffness correction, 2: stiffness and
   kinematic correction), measured by a simulated laser tracker. The simulated robot is the flexible-joint
   plant when use_plant is 1 (needs drives, see jc_robot_has_drives), the quasi-static robot when 0.
   metrics (3 x 5) receives per run Ra, Rz (of the Z deviation), RMS, max and mean of the 3-D error norm,
   all in m; errors (optional, 3 x m x 3) the measured-minus-planned tool positions of each run. */
JOINTCOMP_API jc_status jc_spiral_experiment(jc_robot* robot, int32_t use_plant, double* metrics, int32_t metrics_len,
                                             double* errors, int32_t errors_len);

/** @} */

/** @name Plant
   The robot as the flexible-joint plant of model/plant/flexible_joint_plant.hpp: per joint a motor under
   a PID position controller drives the link through the gear train and the joint spring; the links follow
   the rigid-body dynamics. The plant's own copy of the parameters is used, so the robot handle may be
   freed afterwards. State y = [q, qd, p, pd, integral of the position error] (5 n).
   @{ */

/** A plant of `robot` (which needs drives: jc_robot_has_drives) with the default options; *plant receives the new
    handle. */
JOINTCOMP_API jc_status jc_plant_create(jc_robot* robot, jc_plant** plant);
/** The same with the integrator's and the watchdog's options: options_json is a JSON object (NULL or "{}" for
   the defaults) with any of the keys relative_tolerance, absolute_tolerance (rad), velocity_tolerance_factor
   (1/s), max_step (s, 0: unbounded), max_steps_per_advance, max_order (1 to 5), jacobian_reuse_steps,
   newton_setup_steps, newton_setup_gamma_change, even_steps (true/false), step_past_updates_s (s, 0 to 1),
   tracking_envelope_rad and joint_limit_margin_rad, as PlantOptions in model/plant/flexible_joint_plant.hpp
   and the FMU's integrator.* parameters describe them. step_past_updates_s > 0 lets CVODE step through
   updates shorter than its own step (a reference then takes effect up to one CVODE step late; faster at
   1 ms updates). An unknown key or a value out of range is JC_ERROR_INVALID_ARGUMENT naming it. */
JOINTCOMP_API jc_status jc_plant_create_with_options(jc_robot* robot, const char* options_json, jc_plant** plant);
/** Releases the plant (NULL: nothing to do); JC_ERROR_BUSY while a call still uses it. */
JOINTCOMP_API jc_status jc_plant_free(jc_plant* plant);
/** Number of joints n of the plant. */
JOINTCOMP_API jc_status jc_plant_dof(jc_plant* plant, int32_t* dof);
/** Starts at rest in static equilibrium with the motors at `command` (n), at start_time (s). */
JOINTCOMP_API jc_status jc_plant_reset(jc_plant* plant, const double* command, int32_t command_len, double start_time);
/** The controller follows `position` (n) from now on, extrapolated with `velocity` (n) and the acceleration
   seen between the last two updates, until the next update. A joint given a velocity of exactly 0 stops:
   its reference holds `position` however long the next update takes. */
JOINTCOMP_API jc_status jc_plant_set_reference(jc_plant* plant, const double* position, int32_t position_len,
                                               const double* velocity, int32_t velocity_len);
/** Wrench (6) applied by the environment at the tool, as for jc_robot_set_tool_wrench. */
JOINTCOMP_API jc_status jc_plant_set_tool_wrench(jc_plant* plant, const double* wrench, int32_t wrench_len);
/** Payload of `mass` kg (>= 0) with its centre of mass com (3, m, tool frame). */
JOINTCOMP_API jc_status jc_plant_set_payload(jc_plant* plant, double mass, const double* com, int32_t com_len);
/** Integrates to end_time (s), which must be after the plant's time. JC_ERROR_SOLVER when CVODE fails; the
   plant is then left at the last good time. JC_ERROR_PLANT_LIMIT when the run ends with a link beyond
   its joint limits (by more than the margin) or a drive beyond its tracking envelope, as a drive's
   watchdog would stop it: the plant is at end_time and refuses to advance until reset or restored. */
JOINTCOMP_API jc_status jc_plant_advance(jc_plant* plant, double end_time);
/** The watchdog's limits: the largest following error |reference - motor position| (rad, > 0; 0.2 when
   the plant is created) and how far a link may go beyond its joint limits (rad, >= 0; 0.02). */
JOINTCOMP_API jc_status jc_plant_set_watchdog(jc_plant* plant, double tracking_envelope_rad,
                                              double joint_limit_margin_rad);
/** The plant's time (s). */
JOINTCOMP_API jc_status jc_plant_time(jc_plant* plant, double* time);
/** Outputs, n values each: link positions q and velocities qd, motor positions p and velocities pd (joint
   units: motor angles divided by the gear ratios), and the motor torques the controller applies now. */
JOINTCOMP_API jc_status jc_plant_link_positions(jc_plant* plant, double* values, int32_t values_len);
/** Link velocities qd (n). */
JOINTCOMP_API jc_status jc_plant_link_velocities(jc_plant* plant, double* values, int32_t values_len);
/** Motor positions p (n, joint units). */
JOINTCOMP_API jc_status jc_plant_motor_positions(jc_plant* plant, double* values, int32_t values_len);
/** Motor velocities pd (n, joint units). */
JOINTCOMP_API jc_status jc_plant_motor_velocities(jc_plant* plant, double* values, int32_t values_len);
/** The motor torques (n) the controller applies now. */
JOINTCOMP_API jc_status jc_plant_motor_torques(jc_plant* plant, double* values, int32_t values_len);
/** The integrator's state y (5 n): link positions, link velocities, motor positions, motor velocities and
   the controller's integral of the motor position error, n each. Reading it changes nothing in the run. */
JOINTCOMP_API jc_status jc_plant_state(jc_plant* plant, double* state, int32_t state_len);
/** Integrator counts (5): steps, right-hand sides, Jacobians, error-test failures, convergence failures. */
JOINTCOMP_API jc_status jc_plant_statistics(jc_plant* plant, int64_t* counts, int32_t counts_len);
/** Saving and restoring: a snapshot is everything needed to continue exactly (restoring it and advancing
   gives the same results, bit for bit, as advancing from the moment it was saved). It is an array of
   *size doubles, to be restored only into a plant of the same robot. */
JOINTCOMP_API jc_status jc_plant_snapshot_size(jc_plant* plant, int32_t* size);
/** Saves the plant's snapshot into snapshot (jc_plant_snapshot_size values). */
JOINTCOMP_API jc_status jc_plant_save(jc_plant* plant, double* snapshot, int32_t snapshot_len);
/** Restores a snapshot jc_plant_save took from a plant of the same robot. */
JOINTCOMP_API jc_status jc_plant_restore(jc_plant* plant, const double* snapshot, int32_t snapshot_len);

/** @} */

/** @name Accuracy metrics (as scored in the paper)
    @{ */

/** Metrics of m error vectors (m x 3, m >= 1, measured minus nominal, m): metrics (5) receives Ra (mean
   |z|), Rz (max z - min z) of the Z components, and RMS, max and mean of the norms. */
JOINTCOMP_API jc_status jc_accuracy_metrics(const double* errors, int32_t errors_len, double* metrics,
                                            int32_t metrics_len);
/** Ra = mean |z_k| of Z deviations z (at least 1). */
JOINTCOMP_API jc_status jc_average_absolute_deviation(const double* z, int32_t z_len, double* ra);
/** Rz = max z_k - min z_k of Z deviations z (at least 1). */
JOINTCOMP_API jc_status jc_peak_to_peak_deviation(const double* z, int32_t z_len, double* rz);

/** @} */

/** @name Identification, calibration and discovery from measurement campaigns
   Campaign files are in jointcomp's measurement-campaign format (see docs in model/io and
   jointcomp import-ipa for the IPA UR10 data). A list of files is one string with the paths separated
   by newlines ('\n'). options_json is a JSON object (NULL or "{}" for the defaults) with the keys listed
   at each function; an unknown key or a value of the wrong type or range is JC_ERROR_INVALID_ARGUMENT
   naming the key. A malformed campaign is JC_ERROR_FILE naming the file, line and column.
   The input robot is never changed: results come as a new robot handle (free it with jc_robot_free) and a
   report handle (jc_report_json, jc_report_summary, jc_report_free); either output pointer may be NULL
   when not wanted. These calls read only the input robot's model, which never changes, so they neither
   wait for nor hold up other calls on that handle, even while a discovery runs for seconds.
   @{ */

/** Simulates a measurement campaign with `truth` as the real robot (its geometry, effects and, for the
   plant, drives), with laser-tracker and level noise, and writes it to campaign_path (whole or not at
   all). options: "protocol" (required): "stiffness", "joint-sweep", "joint2-sweep", "back-and-forth",
   "spiral" or "random"; "seed" (integer >= 0, default 1); "noise" (default true); "plant" (default false:
   sweeps and the spiral run on the flexible-joint plant; needs drives); sweeps: "joint" (1-based, default
   2), "from_deg", "to_deg", "step_deg", "settle_s", "cycles"; "count" (random poses); "pose_deg" (n joint
   angles of the stiffness pose and of the sweep's other joints); "warm_up": [rise_degc, time_constant_s,
   start_degc] (the last two optional: 1800 s, 20 degC), temperatures of a robot warming up, which the
   truth's thermal effects follow (quasi-static protocols). */
JOINTCOMP_API jc_status jc_simulate_campaign(jc_robot* truth, const char* options_json, const char* campaign_path);
/** Joint stiffness from a stiffness campaign, by the local (axis by axis) and the global (Cartesian)
   methods. *identified: `nominal` with the stiffness of the method chosen by "method": "local" (default)
   or "global". */
JOINTCOMP_API jc_status jc_identify_stiffness(jc_robot* nominal, const char* campaign_path, const char* options_json,
                                              jc_robot** identified, jc_report** report);
/** Harmonics of the transmission error of one joint from a sweep of that joint. options: "joint" (1-based,
   default 2), "stage" (1 = motor, k = input of gear stage k, stages + 1 = output; default 2), "orders"
   (candidate orders, cycles per revolution of that stage; default [1, 2, 3, 4, 5, 6]). *identified:
   `nominal` with the significant harmonics in its transmission-error effect. */
JOINTCOMP_API jc_status jc_identify_transmission_error(jc_robot* nominal, const char* campaign_path,
                                                       const char* options_json, jc_robot** identified,
                                                       jc_report** report);
/** Kinematic calibration: instrument frame, target, joint offsets, joint placements and compliance (the
   identifiable subset) from one campaign, or several (campaign_path: paths separated by newlines; campaigns
   from different instrument set-ups each get their own frame); held-out campaigns (holdout_paths, may be NULL) are
   checked with only their instrument frame re-fitted. options: "loss": "huber" (default), "cauchy" or "none";
   "loss_scale_mm" (> 0; default: from the residuals); "pivot_threshold" (default 1e-4); "fixed" (names of
   parameters held at nominal, as the report names them); "max_offset_deg" (5.73), "max_placement_shift_mm"
   (20), "max_placement_turn_deg" (2.86): a fit whose joint zero, axis position or axis direction moves further
   is refused with JC_ERROR_INVALID_ARGUMENT naming the joint. *calibrated: the corrected robot. */
JOINTCOMP_API jc_status jc_calibrate(jc_robot* nominal, const char* campaign_path, const char* holdout_paths,
                                     const char* options_json, jc_robot** calibrated, jc_report** report);
/** Residual discovery: the effects the model misses, added one at a time while they lower the time-blocked
   cross-validated error and the BIC (see model/identify/discovery.hpp). campaign_paths: the fitted
   campaigns (at least one); holdout_paths: NULL or the held-out ones. options: "base": "textbook" (default,
   as jc_calibrate fits it) or "frame"; "max_steps" (default 8); "max_harmonic_order" (default 4); "folds"
   (default 5); "min_cv_gain" (default 0.02); "noise_floor_mm" (default: from the campaigns); "types" (effect
   types to try, default all); "loss" and the geometry limits as for jc_calibrate;
   "table_knots" (default [16, 32, 64, 128]), "max_prior_weight" (10), "max_ridge_weight" (1),
   "transfer_significance" (3), "min_group_share" (0.05), "angle_ranges" (5), "pairs" (true). *extended: the
   robot with the discovered effects. */
JOINTCOMP_API jc_status jc_discover(jc_robot* nominal, const char* campaign_paths, const char* holdout_paths,
                                    const char* options_json, jc_robot** extended, jc_report** report);
/** The report as JSON (the same document the command-line tool writes as report.json); buffer as for
   jc_robot_name. */
JOINTCOMP_API jc_status jc_report_json(jc_report* report, char* buffer, int32_t capacity, int32_t* length);
/** The report as a readable summary; buffer as for jc_robot_name. */
JOINTCOMP_API jc_status jc_report_summary(jc_report* report, char* buffer, int32_t capacity, int32_t* length);
/** Releases the report (NULL: nothing to do). */
JOINTCOMP_API jc_status jc_report_free(jc_report* report);

/** @} */

/** @name The spiral with a given truth (Monte Carlo over parameter distributions, issue 19)
    @{ */
/** jc_spiral_experiment with the simulated robot's truth given instead of the built-in perturbation: the
   three runs are compensated with `nominal`'s parameters and followed by `truth` (its joint errors, its
   geometry, and its drives when use_plant is 1), measured by the same simulated tracker. Both robots must
   have the same number of joints; the spiral is planned with `nominal`. metrics and errors as for
   jc_spiral_experiment. Neither handle is changed or locked (their models are immutable). */
JOINTCOMP_API jc_status jc_spiral_experiment_truth(jc_robot* nominal, jc_robot* truth, int32_t use_plant,
                                                   double* metrics, int32_t metrics_len, double* errors,
                                                   int32_t errors_len);

/** @} */

/** @name Monte Carlo of the spiral: one job, many truths (issue 44)
   A jc_spiral_job holds what every draw of a Monte Carlo shares: the spiral planned with `nominal` and the
   three runs' references compensated with its parameters, computed once by jc_spiral_job_create (use_plant
   as for jc_spiral_experiment_truth, the drives being nominal's). Each jc_spiral_job_run then simulates one
   truth only: the nominal robot with its parameters replaced by `values`. The job keeps its own copy of the
   model (the robot handle may be freed after creating it) and never changes, so runs on one job proceed in
   parallel from several threads. jc_spiral_job_run(job, nominal values, 7) equals
   jc_spiral_experiment_truth(nominal, nominal, ...) with that tracker seed.
   @{ */
typedef struct jc_spiral_job jc_spiral_job; /**< a spiral prepared for many truths */
/** Plans and compensates the spiral with `nominal` (use_plant: 1 for the flexible-joint plant, needing drives);
 *job receives the new handle. */
JOINTCOMP_API jc_status jc_spiral_job_create(jc_robot* nominal, int32_t use_plant, jc_spiral_job** job);
/** Releases the job (NULL: nothing to do); JC_ERROR_BUSY while a run still uses it. */
JOINTCOMP_API jc_status jc_spiral_job_free(jc_spiral_job* job);
/** *samples receives m, the planned spiral's number of samples; *parameters p, the truth's parameters. */
JOINTCOMP_API jc_status jc_spiral_job_sizes(jc_spiral_job* job, int32_t* samples, int32_t* parameters);
/** The planned spiral's time (m, s). */
JOINTCOMP_API jc_status jc_spiral_job_time(jc_spiral_job* job, double* time, int32_t time_len);
/** The truth's parameters as a JSON array, in the order jc_spiral_job_run takes them, each {"name", "value"
   (the nominal's), "law"}: first every effect's (its names, unit in the name: "joint_2.stiffness_nm_per_rad"),
   then the geometry's deviations from the URDF (value 0), per joint "J.offset_rad" (unless an effect has
   that name already), "J.placement_{dx,dy,dz}_m" and "J.placement_{rx,ry,rz}_rad", the joint's origin
   becoming origin * Trans(d) * Exp(r) * Rot(axis, offset). "law" is how jc_spiral_experiment perturbs the
   parameter, {"scale": s, "relative": true} for value * (1 + s U(-1, 1)), false for value + s U(-1, 1); null
   for the geometry, which it does not perturb. buffer as for jc_robot_name. */
JOINTCOMP_API jc_status jc_spiral_job_parameters(jc_spiral_job* job, char* buffer, int32_t capacity, int32_t* length);
/** One truth follows the prepared runs: values (p), the truth's parameters; noise_seed (>= 0), the simulated
   tracker's; metrics (3 x 5) and errors (optional, 3 x m x 3) as for jc_spiral_experiment. A value out of
   its parameter's range (a stiffness <= 0) is JC_ERROR_INVALID_ARGUMENT naming the parameter. */
JOINTCOMP_API jc_status jc_spiral_job_run(jc_spiral_job* job, const double* values, int32_t values_len,
                                          int64_t noise_seed, double* metrics, int32_t metrics_len, double* errors,
                                          int32_t errors_len);

/** Poses of the tool (count x 16, as jc_forward_kinematics) at count joint vectors q (count x n): one call for a
   batch. */
JOINTCOMP_API jc_status jc_forward_kinematics_batch(jc_robot* robot, int32_t count, const double* q, int32_t q_len,
                                                    double* poses, int32_t poses_len);

/** Loads the robot from URDF text (no file needed: what a task sent to another machine carries) with its
   parameters as JSON text (NULL: kinematics and dynamics only); the chain as for jc_robot_load. */
JOINTCOMP_API jc_status jc_robot_load_text(const char* urdf_text, const char* parameters_json, jc_robot** robot);

/** @} */

/** @name The paper's whole method on a given truth (issue 43)
    @{ */
/** Measure, identify, compensate, as `jointcomp paper` does: the paper's identification campaigns are simulated
   on `truth` with the instruments' noise (the stiffness protocol under known loads, measured by the laser
   tracker and two levels; the joint-2 sweep from -50 to +50 deg, by the tracker; both quasi-static), the joint
   stiffnesses and joint 2's transmission error are identified against `nominal`'s parameters
   (model/identify), and the spiral is compensated with the identified model and followed by `truth`.
   options_json (may be NULL): "seed" (the campaigns' noise, a whole number from 0 to 2^53; default 2012, as
   `jointcomp paper --seed`), "use_plant" (true: the truth is the flexible-joint plant, needs its drives;
   default false), "dynamic_correction" (true: a fourth run with the dynamic correction of the identified
   model, needs use_plant; default false), "feed_rate_m_per_s" (0.003 to 2, default 0.03; acceleration and
   jerk scale with it). metrics (3 x 5, or 4 x 5 with dynamic_correction; all in m): per run Ra, Rz, RMS, max
   and mean, the runs of jc_spiral_experiment with the identified model's corrections. *identified (NULL: not
   wanted): `nominal` with the identified parameters, and nominal's drives. *report (NULL: not wanted): both
   identifications' reports in one JSON document ("format": "jointcomp-identification-reports/1", which
   `jointcomp montecarlo --report` takes once written to a file; truths included) and their summaries.
   Outputs are written only on success. JC_ERROR_INVALID_ARGUMENT for bad handles, options or metrics length;
   JC_ERROR_FILE when a campaign cannot identify what is asked; JC_ERROR_SOLVER when the simulated robot
   does not settle. Neither robot handle is changed or locked. */
JOINTCOMP_API jc_status jc_identify_and_compensate(jc_robot* nominal, jc_robot* truth, const char* options_json,
                                                   double* metrics, int32_t metrics_len, jc_robot** identified,
                                                   jc_report** report);

/** @} */

/** @name Dynamic compensation of a trajectory with time (issue 18)
    @{ */
/** The references that make the modelled robot (flexible joints, the drives and controller of the
   parameters' "plant" object, every effect, the handle's payload and tool wrench) put its links on a
   planned trajectory at any speed, computed offline (model/plant/dynamic_compensation.hpp): m samples at
   `times` (m, finite and increasing), planned positions and velocities (m x n each, m = times_len);
   references (m x n) and, optional, their velocities (m x n: what the controller interpolates with; NULL
   and 0 for none). *runs and *max_link_error (optional) receive the runs of the nominal plant the
   refinement made and the largest link error left on it (rad). JC_ERROR_INVALID_ARGUMENT when the
   parameters have no "plant" object or the trajectory is malformed (fewer than three samples, say);
   JC_ERROR_SOLVER when the refinement does not reach 2e-6 rad; JC_ERROR_UNREACHABLE when a reference
   leaves the joint limits. */
JOINTCOMP_API jc_status jc_compensate_trajectory_dynamic(jc_robot* robot, const double* times, int32_t times_len,
                                                         const double* planned, int32_t planned_len,
                                                         const double* velocities, int32_t velocities_len,
                                                         double* references, int32_t references_len,
                                                         double* reference_velocities, int32_t reference_velocities_len,
                                                         int32_t* runs, double* max_link_error);

/** @} */

#ifdef __cplusplus
}
#endif

#endif /* JOINTCOMP_JOINTCOMP_H */

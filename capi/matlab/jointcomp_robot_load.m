function robot = jointcomp_robot_load(urdf_path, parameter_path)
%JOINTCOMP_ROBOT_LOAD Loads a robot: its URDF and its joint-error parameter file.
%   ROBOT = JOINTCOMP_ROBOT_LOAD(URDF_PATH, PARAMETER_PATH) returns the robot's handle (a lib.pointer)
%   for the calllib('jointcomp', 'jc_...') calls. Release it with JOINTCOMP_ROBOT_FREE.
jointcomp_load();
handle = libpointer('voidPtrPtr');
status = calllib('jointcomp', 'jc_robot_load', urdf_path, parameter_path, handle);
jointcomp_check(status);
robot = handle.Value;
end

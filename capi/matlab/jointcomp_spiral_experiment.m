function [ra, rz, metrics] = jointcomp_spiral_experiment(robot, use_plant)
%JOINTCOMP_SPIRAL_EXPERIMENT The paper's spiral experiment (Olabi et al., IEEE ICIT 2012, Table II).
%   [RA, RZ, METRICS] = JOINTCOMP_SPIRAL_EXPERIMENT(ROBOT, USE_PLANT) runs the three runs (without
%   correction, stiffness correction, stiffness and kinematic correction) on a simulated robot: the
%   flexible-joint plant when USE_PLANT is true (the parameters must describe the drives), else the
%   quasi-static robot. RA and RZ are 3 x 1 (m); METRICS is 3 x 5: Ra, Rz, RMS, max, mean (m).
%   Without USE_PLANT, the plant is used when the parameters describe the drives.
if nargin < 2
    has_drives = libpointer('int32Ptr', int32(0));
    jointcomp_check(calllib('jointcomp', 'jc_robot_has_drives', robot, has_drives));
    use_plant = has_drives.Value == 1;
end
values = libpointer('doublePtr', zeros(15, 1));
jointcomp_check(calllib('jointcomp', 'jc_spiral_experiment', robot, int32(use_plant), values, int32(15), [], int32(0)));
metrics = reshape(values.Value, 5, 3)';
ra = metrics(:, 1);
rz = metrics(:, 2);
end

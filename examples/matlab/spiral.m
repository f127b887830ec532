% The paper's spiral (Olabi et al., IEEE ICIT 2012, Table II) through the jointcomp C API from MATLAB:
% the three runs of a simulated RX170 and their Ra and Rz.
%
% Run from this folder in a jointcomp source checkout, with the library built (bash run.sh) and
%   setenv('JOINTCOMP_LIBRARY', '<checkout>/build/release/capi/libjointcomp.so.1')
% or from an installed tree, with <prefix>/share/jointcomp/matlab on the path instead.
here = fileparts(mfilename('fullpath'));
addpath(fullfile(here, '..', '..', 'capi', 'matlab'));
data = fullfile(here, '..', '..', 'model');

jointcomp_load();
fprintf('jointcomp %s\n', calllib('jointcomp', 'jc_version'));
robot = jointcomp_robot_load(fullfile(data, 'robots', 'rx170.urdf'), fullfile(data, 'params', 'rx170.json'));

% The tool over the spiral's first point: forward kinematics of the planned joints.
count = libpointer('int32Ptr', int32(0));
jointcomp_check(calllib('jointcomp', 'jc_spiral_sample_count', robot, count));
m = double(count.Value);
q = libpointer('doublePtr', zeros(6 * m, 1));
jointcomp_check(calllib('jointcomp', 'jc_spiral_plan', robot, [], int32(0), [], int32(0), q, int32(6 * m), [], int32(0)));
first = q.Value(1:6);
pose = jointcomp_forward_kinematics(robot, first);
fprintf('spiral: %d samples, starting at (%.1f, %.1f, %.1f) mm\n', m, pose(1:3, 4) * 1e3);

% The three runs.
[ra, rz] = jointcomp_spiral_experiment(robot);
names = {'without correction', 'stiffness correction', 'stiffness and kinematic correction'};
fprintf('%-36s %9s %9s\n', 'run', 'Ra [mm]', 'Rz [mm]');
for k = 1:3
    fprintf('%-36s %9.4f %9.4f\n', names{k}, ra(k) * 1e3, rz(k) * 1e3);
end

jointcomp_robot_free(robot);

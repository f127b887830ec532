function pose = jointcomp_forward_kinematics(robot, q)
%JOINTCOMP_FORWARD_KINEMATICS Tool pose (4 x 4 homogeneous transform, base frame) at joint positions Q (rad).
n = libpointer('int32Ptr', int32(0));
jointcomp_check(calllib('jointcomp', 'jc_robot_dof', robot, n));
if numel(q) ~= n.Value
    error('jointcomp:q', 'q has %d values, the robot has %d joints', numel(q), n.Value);
end
values = libpointer('doublePtr', zeros(16, 1));
jointcomp_check(calllib('jointcomp', 'jc_forward_kinematics', robot, double(q(:)), int32(numel(q)), values, int32(16)));
% The C API's matrices are row-major, MATLAB's column-major.
pose = reshape(values.Value, 4, 4)';
end

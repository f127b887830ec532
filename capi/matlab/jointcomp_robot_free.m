function jointcomp_robot_free(robot)
%JOINTCOMP_ROBOT_FREE Releases a robot handle from JOINTCOMP_ROBOT_LOAD.
jointcomp_check(calllib('jointcomp', 'jc_robot_free', robot));
end

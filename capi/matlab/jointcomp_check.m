function jointcomp_check(status)
%JOINTCOMP_CHECK Raises a MATLAB error for a failed jointcomp call.
%   JOINTCOMP_CHECK(STATUS) does nothing for STATUS 0 (JC_OK); otherwise it raises an error whose
%   identifier names the status (e.g. jointcomp:JC_ERROR_SOLVER) and whose message is the library's.
if status == 0
    return;
end
name = calllib('jointcomp', 'jc_status_name', status);
message = calllib('jointcomp', 'jc_last_error');
error(['jointcomp:' name], '%s', message);
end

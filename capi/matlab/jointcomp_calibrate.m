function [calibrated, report] = jointcomp_calibrate(robot, campaign_path, holdout_paths, options)
%JOINTCOMP_CALIBRATE Kinematic calibration of ROBOT from a measurement campaign file.
%   [CALIBRATED, REPORT] = JOINTCOMP_CALIBRATE(ROBOT, CAMPAIGN_PATH, HOLDOUT_PATHS, OPTIONS) fits the
%   instrument frame, target, joint offsets, joint placements and compliance (the identifiable subset) on
%   CAMPAIGN_PATH (one file, or a cell array of files: campaigns from different instrument set-ups each
%   get their own frame) and checks the result on HOLDOUT_PATHS (a cell array of campaign files, may be {}).
%   OPTIONS is a struct with the fields of jc_calibrate's options_json (loss, loss_scale_mm,
%   pivot_threshold, fixed, max_offset_deg, max_placement_shift_mm, max_placement_turn_deg), may be omitted.
%   CALIBRATED is a new robot handle (free it with
%   JOINTCOMP_ROBOT_FREE); REPORT is the report decoded from JSON (jsondecode).
if nargin < 3
    holdout_paths = {};
end
if nargin < 4
    options = struct();
end
holdouts = strjoin(holdout_paths, newline);
if iscell(campaign_path)
    campaign_path = strjoin(campaign_path, newline);
end
calibrated_handle = libpointer('voidPtrPtr');
report_handle = libpointer('voidPtrPtr');
jointcomp_check(calllib('jointcomp', 'jc_calibrate', robot, campaign_path, holdouts, jsonencode(options), ...
    calibrated_handle, report_handle));
calibrated = calibrated_handle.Value;
report_pointer = report_handle.Value;
length = libpointer('int32Ptr', int32(0));
jointcomp_check(calllib('jointcomp', 'jc_report_json', report_pointer, [], int32(0), length));
buffer = libpointer('int8Ptr', zeros(1, double(length.Value) + 1, 'int8'));
jointcomp_check(calllib('jointcomp', 'jc_report_json', report_pointer, buffer, length.Value + 1, length));
text = char(buffer.Value(1:length.Value));
jointcomp_check(calllib('jointcomp', 'jc_report_free', report_pointer));
report = jsondecode(text);
end

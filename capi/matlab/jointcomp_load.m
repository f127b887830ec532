function jointcomp_load(library_path)
%JOINTCOMP_LOAD Loads libjointcomp under the alias 'jointcomp' for calllib.
%   JOINTCOMP_LOAD() finds the library through the JOINTCOMP_LIBRARY environment variable, else by its
%   soname libjointcomp.so.1 on the system's library path (LD_LIBRARY_PATH).
%   JOINTCOMP_LOAD(LIBRARY_PATH) loads the library at LIBRARY_PATH.
%   The header is jointcomp.h beside this folder in the source tree (capi/include/jointcomp) or in the
%   installed tree (<prefix>/include/jointcomp). MATLAB's loadlibrary needs a supported C compiler on Linux.
%   Every call returns a status; pass it to JOINTCOMP_CHECK to turn errors into MATLAB errors.
if libisloaded('jointcomp')
    return;
end
if nargin < 1 || isempty(library_path)
    library_path = getenv('JOINTCOMP_LIBRARY');
end
if isempty(library_path)
    library_path = 'libjointcomp.so.1';
end
here = fileparts(mfilename('fullpath'));
headers = {fullfile(here, '..', 'include', 'jointcomp', 'jointcomp.h'), ...
           fullfile(here, '..', '..', '..', 'include', 'jointcomp', 'jointcomp.h')};
header = '';
for k = 1:numel(headers)
    if exist(headers{k}, 'file')
        header = headers{k};
        break;
    end
end
if isempty(header)
    error('jointcomp:header', 'jointcomp.h not found beside %s', here);
end
loadlibrary(library_path, header, 'alias', 'jointcomp');
abi = calllib('jointcomp', 'jc_abi_version');
if abi ~= 1
    unloadlibrary('jointcomp');
    error('jointcomp:abi', 'libjointcomp has ABI version %d, these functions need 1', abi);
end
end

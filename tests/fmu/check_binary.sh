#!/usr/bin/env bash
# The FMU binary needs nothing on the target machine beyond the C runtime (libc, libm, libpthread), libgcc_s
# (and the loader), no newer GLIBC symbol version than NEWEST_GLIBC ("any": not checked, and libstdc++
# allowed), and exports exactly the functions of the FMI API (every one of them, nothing else).
#   check_binary.sh <2|3> <unzipped FMU folder> <fmu/fmiN_api.hpp> [NEWEST_GLIBC]
set -euo pipefail
version="$1" folder="$2" api="$3" newest_allowed="${4:-any}"
if [ "$version" = 2 ]; then platform=linux64 count=44; else platform=x86_64-linux count=75; fi
binary="$folder/binaries/$platform/jointcomp.so"
[ -f "$binary" ] || { echo "no binary at $binary"; exit 1; }
status=0

needed=$(readelf -d "$binary" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p' | sort)
echo "NEEDED: $(echo $needed)"
for library in $needed; do
  case "$library" in
    libc.so.6|libm.so.6|libpthread.so.0|libgcc_s.so.1|ld-linux-x86-64.so.2) ;;
    libstdc++.so.6) [ "$newest_allowed" = any ] || { echo "needs libstdc++ (its C++ runtime is not static)"; status=1; } ;;
    *) echo "not allowed on the target machine: $library"; status=1 ;;
  esac
done

# The symbol versions the target's C library must have: the newest decides which distributions load it.
newest=$(objdump -T "$binary" | grep -o '(GLIBC_[0-9.]*)' | tr -d '()' | sed 's/GLIBC_//' | sort -V | tail -1)
echo "newest GLIBC symbol version needed: $newest"
echo "  by: $(objdump -T "$binary" | grep -F "(GLIBC_$newest)" | awk '{print $NF}' | sort | tr '\n' ' ')"
if [ "$newest_allowed" != any ] &&
  [ "$(printf '%s\n%s\n' "$newest" "$newest_allowed" | sort -V | tail -1)" != "$newest_allowed" ]; then
  echo "needs GLIBC $newest, more than $newest_allowed"
  status=1
fi
if [ "$newest_allowed" != any ] && objdump -T "$binary" | grep -c -E 'GLIBCXX_|CXXABI_' >/dev/null; then
  echo "needs libstdc++ symbols:"
  objdump -T "$binary" | grep -E 'GLIBCXX_|CXXABI_' | head
  status=1
fi
if readelf -d "$binary" | grep -c -E 'R(UN)?PATH' >/dev/null; then echo "the binary has an RPATH/RUNPATH"; status=1; fi

exported=$(nm -D --defined-only "$binary" | awk '{print $3}' | sort)
# Declarations may span lines (the return type on a line of its own): read the header as one line.
expected=$(tr '\n' ' ' <"$api" | grep -o "JOINTCOMP_FMI${version}_EXPORT [^(;]*[ *]fmi${version}[A-Za-z0-9]* *(" |
  sed -E "s/.*[ *](fmi${version}[A-Za-z0-9]*) *\\($/\\1/" | sort)
[ "$(echo "$expected" | wc -l)" = "$count" ] || { echo "$api declares $(echo "$expected" | wc -l) functions, the standard $count"; status=1; }
if [ "$exported" != "$expected" ]; then
  echo "exported symbols differ from the FMI $version API:"
  diff <(echo "$expected") <(echo "$exported") || true
  status=1
fi
echo "exported: $(echo "$exported" | wc -l) functions, all fmi${version}*"
exit $status

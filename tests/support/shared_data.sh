# For shell tests that need data the repository does not carry (the one setting JOINTCOMP_SHARED, as
# shared_data.hpp for the C++ tests). Source it, then
#   require_shared_file VARIABLE "what it is" relative/path/in/shared
# sets VARIABLE to the file's path, or prints a named skip and exits 77 (CTest's SKIP_RETURN_CODE).
require_shared_file() {
  local variable="$1" what="$2" relative="$3"
  if [ -z "${JOINTCOMP_SHARED:-}" ]; then
    echo "skipped: $what not found: JOINTCOMP_SHARED is not set (a folder with $relative)"
    exit 77
  fi
  if [ ! -f "$JOINTCOMP_SHARED/$relative" ]; then
    echo "skipped: $what not found at $JOINTCOMP_SHARED/$relative"
    exit 77
  fi
  printf -v "$variable" '%s' "$JOINTCOMP_SHARED/$relative"
}

// The public header compiles as C++ (with the project's warnings as errors) and links from C++.
#include <jointcomp/jointcomp.h>

#include <cstdio>
#include <cstring>

int main() {
  jc_robot* robot = nullptr;
  const jc_status status = jc_robot_load(nullptr, nullptr, &robot);
  const bool ok = jc_abi_version() == JC_ABI_VERSION && status == JC_ERROR_INVALID_ARGUMENT && robot == nullptr &&
                  std::strstr(jc_last_error(), "jc_robot_load") != nullptr;
  std::printf("test_capi_header: %s\n", ok ? "ok" : "failed");
  return ok ? 0 : 1;
}

// The FMU binaries load on Linux distributions much older than the one that builds them (RHEL 7, Ubuntu
// 14.04 and later: GLIBC 2.17, tests/fmu/check_binary.sh). The C++ runtime is linked in statically, and
// the few C library functions that it, the model or libm's headers bind to recent symbol versions are
// routed here (ld --wrap, fmu/CMakeLists.txt) and on to their x86_64 baseline versions (GLIBC_2.2.5), which
// every glibc since keeps with the same behaviour. Only for x86_64 with glibc; other targets link the
// default versions and the shared C++ runtime.
#include <cerrno>
#include <cstddef>
#include <cstdint>

#include <pthread.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

extern "C" {

// The baseline versions, under names of our own so that nothing else binds to them by accident.
double jointcomp_baseline_hypot(double, double);
double jointcomp_baseline_pow(double, double);
int jointcomp_baseline_pthread_once(pthread_once_t*, void (*)());
int jointcomp_baseline_xstat64(int, const char*, struct stat*);
int jointcomp_baseline_lxstat64(int, const char*, struct stat*);
int jointcomp_baseline_fxstat64(int, int, struct stat*);
__asm__(".symver jointcomp_baseline_hypot, hypot@GLIBC_2.2.5");
__asm__(".symver jointcomp_baseline_pow, pow@GLIBC_2.2.5");
__asm__(".symver jointcomp_baseline_pthread_once, pthread_once@GLIBC_2.2.5");
__asm__(".symver jointcomp_baseline_xstat64, __xstat64@GLIBC_2.2.5");
__asm__(".symver jointcomp_baseline_lxstat64, __lxstat64@GLIBC_2.2.5");
__asm__(".symver jointcomp_baseline_fxstat64, __fxstat64@GLIBC_2.2.5");

// hypot@GLIBC_2.35 and pow@GLIBC_2.29 differ from the old ones only in how they report errors (errno).
double __wrap_hypot(double x, double y) { return jointcomp_baseline_hypot(x, y); }
double __wrap_pow(double x, double y) { return jointcomp_baseline_pow(x, y); }

// pthread_once@GLIBC_2.34 is the old function moved from libpthread into libc.
int __wrap_pthread_once(pthread_once_t* once, void (*routine)()) {
  return jointcomp_baseline_pthread_once(once, routine);
}

// stat, lstat, fstat and fstat64 became functions in GLIBC 2.33; before, they were inline calls of these.
constexpr int kStatVersion = 1;  // _STAT_VER of x86_64
int __wrap_stat(const char* path, struct stat* info) { return jointcomp_baseline_xstat64(kStatVersion, path, info); }
int __wrap_lstat(const char* path, struct stat* info) { return jointcomp_baseline_lxstat64(kStatVersion, path, info); }
int __wrap_fstat64(int descriptor, struct stat* info) {
  return jointcomp_baseline_fxstat64(kStatVersion, descriptor, info);
}
int __wrap_fstat(int descriptor, struct stat* info) {  // x86_64: struct stat is struct stat64
  return jointcomp_baseline_fxstat64(kStatVersion, descriptor, info);
}

// GLIBC 2.32's flag lets libstdc++ skip atomic reference counts in single-threaded programs; "not known
// to be single-threaded" is always correct (an FMU may be stepped from any thread).
char __wrap___libc_single_threaded = 0;

// getentropy (GLIBC 2.25) and arc4random (2.36), which libstdc++'s std::random_device may use, from the
// kernel's getrandom (Linux 3.17).
int __wrap_getentropy(void* buffer, std::size_t length) {
  if (length > 256) {
    errno = EIO;
    return -1;
  }
  auto* out = static_cast<unsigned char*>(buffer);
  while (length > 0) {
    const long got = syscall(SYS_getrandom, out, length, 0);
    if (got < 0) {
      if (errno == EINTR) continue;
      return -1;
    }
    out += got;
    length -= static_cast<std::size_t>(got);
  }
  return 0;
}

std::uint32_t __wrap_arc4random() {
  std::uint32_t value = 0;
  if (__wrap_getentropy(&value, sizeof value) != 0) __builtin_trap();  // arc4random cannot fail either
  return value;
}

}  // extern "C"

// The static C++ runtime's emergency exception pool (72 KB, allocated when the binary is loaded) belongs
// to this binary alone: freed when the importer unloads the FMU, or each load and unload would leak it.
namespace __gnu_cxx {
void __freeres();
}
__attribute__((destructor)) static void freeTheStaticCxxRuntimesPool() { __gnu_cxx::__freeres(); }

// The linux64 FMU binary loads on glibc 2.17 (the manylinux2014 baseline):
// the link renames each reference to a newer glibc symbol NAME into
// __wrap_NAME (--wrap, see CMakeLists.txt), defined here on the oldest
// version of that function, which computes the same. Compiled without
// link-time optimisation: .symver names must reach the assembler as written.
// The test of the ELF version requirements (tests/python/test_platforms.py)
// names any symbol that a new glibc or GCC adds to the list.
#include <pthread.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

extern "C" {

void* memcpy_glibc_2_2_5(void*, const void*, std::size_t);
double exp_glibc_2_2_5(double);
double log_glibc_2_2_5(double);
double pow_glibc_2_2_5(double, double);
double hypot_glibc_2_2_5(double, double);  // SuiteSparse_config's default hypot
int pthread_once_glibc_2_2_5(int*, void (*)());
// Thread-specific keys and read-write locks: libstdc++'s pmr pools, which
// its from_chars(double) uses, moved from libpthread to libc in glibc 2.34.
int pthread_key_create_glibc_2_2_5(pthread_key_t*, void (*)(void*));
int pthread_key_delete_glibc_2_2_5(pthread_key_t);
void* pthread_getspecific_glibc_2_2_5(pthread_key_t);
int pthread_setspecific_glibc_2_2_5(pthread_key_t, const void*);
int pthread_rwlock_rdlock_glibc_2_2_5(pthread_rwlock_t*);
int pthread_rwlock_wrlock_glibc_2_2_5(pthread_rwlock_t*);
int pthread_rwlock_unlock_glibc_2_2_5(pthread_rwlock_t*);
int __fxstat64(int version, int fd, struct stat64* buf);  // GLIBC_2.2.5, no longer declared
__asm__(".symver memcpy_glibc_2_2_5, memcpy@GLIBC_2.2.5");
__asm__(".symver exp_glibc_2_2_5, exp@GLIBC_2.2.5");
__asm__(".symver log_glibc_2_2_5, log@GLIBC_2.2.5");
__asm__(".symver pow_glibc_2_2_5, pow@GLIBC_2.2.5");
__asm__(".symver hypot_glibc_2_2_5, hypot@GLIBC_2.2.5");
__asm__(".symver pthread_once_glibc_2_2_5, pthread_once@GLIBC_2.2.5");
__asm__(".symver pthread_key_create_glibc_2_2_5, pthread_key_create@GLIBC_2.2.5");
__asm__(".symver pthread_key_delete_glibc_2_2_5, pthread_key_delete@GLIBC_2.2.5");
__asm__(".symver pthread_getspecific_glibc_2_2_5, pthread_getspecific@GLIBC_2.2.5");
__asm__(".symver pthread_setspecific_glibc_2_2_5, pthread_setspecific@GLIBC_2.2.5");
__asm__(".symver pthread_rwlock_rdlock_glibc_2_2_5, pthread_rwlock_rdlock@GLIBC_2.2.5");
__asm__(".symver pthread_rwlock_wrlock_glibc_2_2_5, pthread_rwlock_wrlock@GLIBC_2.2.5");
__asm__(".symver pthread_rwlock_unlock_glibc_2_2_5, pthread_rwlock_unlock@GLIBC_2.2.5");

void* __wrap_memcpy(void* to, const void* from, std::size_t n) { return memcpy_glibc_2_2_5(to, from, n); }
double __wrap_exp(double x) { return exp_glibc_2_2_5(x); }
double __wrap_log(double x) { return log_glibc_2_2_5(x); }
double __wrap_pow(double x, double y) { return pow_glibc_2_2_5(x, y); }
double __wrap_hypot(double x, double y) { return hypot_glibc_2_2_5(x, y); }
int __wrap_pthread_once(int* once, void (*routine)()) { return pthread_once_glibc_2_2_5(once, routine); }
int __wrap_pthread_key_create(pthread_key_t* key, void (*destructor)(void*)) {
  return pthread_key_create_glibc_2_2_5(key, destructor);
}
int __wrap_pthread_key_delete(pthread_key_t key) { return pthread_key_delete_glibc_2_2_5(key); }
void* __wrap_pthread_getspecific(pthread_key_t key) { return pthread_getspecific_glibc_2_2_5(key); }
int __wrap_pthread_setspecific(pthread_key_t key, const void* value) {
  return pthread_setspecific_glibc_2_2_5(key, value);
}
int __wrap_pthread_rwlock_rdlock(pthread_rwlock_t* lock) { return pthread_rwlock_rdlock_glibc_2_2_5(lock); }
int __wrap_pthread_rwlock_wrlock(pthread_rwlock_t* lock) { return pthread_rwlock_wrlock_glibc_2_2_5(lock); }
int __wrap_pthread_rwlock_unlock(pthread_rwlock_t* lock) { return pthread_rwlock_unlock_glibc_2_2_5(lock); }

// fstat64 was a header inline over __fxstat64 before glibc 2.33 (1 is
// _STAT_VER on x86-64).
int __wrap_fstat64(int fd, struct stat64* buf) { return __fxstat64(1, fd, buf); }

// libstdc++'s reference-count fast path for a process without threads
// (glibc 2.32): 0 keeps the atomic path, right in any process.
char __wrap___libc_single_threaded = 0;

// std::random_device's sources (glibc 2.25 and 2.36), which the FMU does not
// use but libstdc++ links: the kernel's getrandom, as glibc implements them.
int __wrap_getentropy(void* buffer, std::size_t length) {
  if (length > 256) {
    errno = EIO;
    return -1;
  }
  auto* bytes = static_cast<unsigned char*>(buffer);
  while (length > 0) {
    const long got = syscall(SYS_getrandom, bytes, length, 0);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return -1;
    bytes += got;
    length -= std::size_t(got);
  }
  return 0;
}

std::uint32_t __wrap_arc4random() {
  std::uint32_t value;
  if (__wrap_getentropy(&value, sizeof value) != 0) std::abort();  // glibc's arc4random aborts too
  return value;
}

}  // extern "C"

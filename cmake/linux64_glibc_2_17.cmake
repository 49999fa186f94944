# The linux64 FMU binary needs nothing newer than glibc 2.17 and no C++
# runtime from the system: libstdc++ is linked in, and each reference to a
# glibc symbol newer than 2.17 (from this compiler's headers and libstdc++)
# goes to a wrapper on the symbol's old version (fmu_src/glibc_2_17.cpp).
# libgcc_s.so.1 stays shared: every glibc system has it (manylinux2014 lists
# it among the system libraries), and the static unwinder of a new GCC would
# need glibc 2.35's _dl_find_object.
#
# MFBD_PORTABLE_LINUX64=OFF keeps the system's shared libstdc++ and glibc's
# current symbol versions: for builds that run here only, such as the
# sanitizer build (scripts/sanitize.sh), where a static libstdc++'s emergency
# exception pool would be left behind by every dlclose of the FMU.
option(MFBD_PORTABLE_LINUX64 "Link libstdc++ statically and bind glibc symbols to 2.17" ON)
set(MFBD_GLIBC_2_17_WRAPPED memcpy exp log pow hypot pthread_once fstat64 __libc_single_threaded getentropy arc4random
    pthread_key_create pthread_key_delete pthread_getspecific pthread_setspecific
    pthread_rwlock_rdlock pthread_rwlock_wrlock pthread_rwlock_unlock)

function(mfbd_link_for_glibc_2_17 target)
  # Always: the FMI functions are the only exports, which also lets the
  # static archives' code bind locally inside the shared object.
  set_property(TARGET ${target} APPEND PROPERTY LINK_DEPENDS ${CMAKE_SOURCE_DIR}/cmake/fmi2_exports.map)
  target_link_options(${target} PRIVATE -Wl,--no-undefined
                      -Wl,--version-script=${CMAKE_SOURCE_DIR}/cmake/fmi2_exports.map)
  if(NOT MFBD_PORTABLE_LINUX64)
    return()
  endif()
  target_sources(${target} PRIVATE ${CMAKE_SOURCE_DIR}/fmu_src/glibc_2_17.cpp)
  set_source_files_properties(${CMAKE_SOURCE_DIR}/fmu_src/glibc_2_17.cpp PROPERTIES COMPILE_OPTIONS -fno-lto)
  set(wraps)
  foreach(symbol ${MFBD_GLIBC_2_17_WRAPPED})
    list(APPEND wraps "-Wl,--wrap=${symbol}")
  endforeach()
  # pthread_once@GLIBC_2.2.5 lives in libpthread before glibc 2.34.
  target_link_options(${target} PRIVATE ${wraps} -static-libstdc++
                      -Wl,--no-as-needed -l:libpthread.so.0 -Wl,--as-needed)
endfunction()

# Copies every shared library BINARY needs, except the C/C++ runtime, next to
# it and gives each copy RUNPATH $ORIGIN, so the FMU's binaries folder is
# self-contained (the loader finds transitive dependencies there too).
# Usage: cmake -DBINARY=<path to .so> -P bundle_dependencies.cmake
get_filename_component(dir "${BINARY}" DIRECTORY)
set(runtime "^(ld-linux.*|libc|libm|libdl|librt|libpthread|libstdc\\+\\+|libgcc_s|linux-vdso)\\.so")
file(GET_RUNTIME_DEPENDENCIES
  LIBRARIES "${BINARY}"
  RESOLVED_DEPENDENCIES_VAR resolved
  UNRESOLVED_DEPENDENCIES_VAR unresolved
  PRE_EXCLUDE_REGEXES "${runtime}")
if(unresolved)
  message(FATAL_ERROR "unresolved libraries of ${BINARY}: ${unresolved}")
endif()
find_program(PATCHELF patchelf REQUIRED)
foreach(lib ${resolved})
  get_filename_component(name "${lib}" NAME)
  if(name MATCHES "${runtime}")
    continue()
  endif()
  file(REAL_PATH "${lib}" real)
  file(COPY_FILE "${real}" "${dir}/${name}")
  execute_process(COMMAND ${PATCHELF} --set-rpath "$ORIGIN" "${dir}/${name}" RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "patchelf failed on ${dir}/${name}")
  endif()
  message(STATUS "bundled ${name}")
endforeach()

# The win64 FMU binary (and the test master fmu_master.exe) from the same
# sources, by a build of its own in build/win64 with the MinGW-w64 toolchain,
# when that toolchain is installed (scripts/setup.sh installs it). Its DLL
# lands in fmu_binaries/win64, which the packer adds to every FMU.
option(MFBD_WIN64 "Cross-compile the win64 FMU binary with MinGW-w64" ON)
set(MFBD_WIN64_TARGET "")
find_program(MFBD_MINGW_CXX x86_64-w64-mingw32-g++-posix)
if(MFBD_WIN64 AND NOT MFBD_MINGW_CXX)
  message(WARNING "x86_64-w64-mingw32-g++-posix not found: FMUs carry linux64 only "
                  "(apt-get install g++-mingw-w64-x86-64-posix, or -DMFBD_WIN64=OFF)")
elseif(MFBD_WIN64)
  include(ExternalProject)
  ExternalProject_Add(win64
    SOURCE_DIR "${CMAKE_SOURCE_DIR}"
    BINARY_DIR "${CMAKE_BINARY_DIR}/win64"
    CMAKE_ARGS
      -DCMAKE_TOOLCHAIN_FILE=${CMAKE_SOURCE_DIR}/cmake/mingw-w64-x86_64.cmake
      -DCMAKE_BUILD_TYPE=${CMAKE_BUILD_TYPE}
      -DCMAKE_C_COMPILER_LAUNCHER=${CMAKE_C_COMPILER_LAUNCHER}
      -DCMAKE_CXX_COMPILER_LAUNCHER=${CMAKE_CXX_COMPILER_LAUNCHER}
      -DFMI2_INCLUDE_DIR=${FMI2_INCLUDE_DIR}
      -DMFBD_FMU_BINARY_ROOT=${MFBD_FMU_BINARY_ROOT}
      -DMFBD_FMU_ONLY=ON
      -DMFBD_KLU_SOURCE_DIR=${MFBD_KLU_SOURCE_DIR}  # fetched once, by this build
    INSTALL_COMMAND ""
    BUILD_ALWAYS ON  # its own build tool decides what is out of date
    BUILD_BYPRODUCTS "${MFBD_FMU_BINARY_ROOT}/win64/mfbd_fmu.dll" "${MFBD_FMU_BINARY_ROOT}/win64/pid_controller.dll"
    USES_TERMINAL_BUILD ON)
  # The FMUs are packed again when the DLL changes.
  set(MFBD_WIN64_TARGET win64 "${MFBD_FMU_BINARY_ROOT}/win64/mfbd_fmu.dll")
endif()

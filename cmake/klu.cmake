# KLU (SuiteSparse: KLU, BTF, AMD, COLAMD, SuiteSparse_config) built from
# one pinned source as the static library SuiteSparse::KLU, the same on
# every platform: Debian has no KLU for MinGW, and the same code on linux64
# and win64 keeps their results together. The sources are those bundled in
# the sdist of klujax 0.2.0 on PyPI (SuiteSparse 7.1.0), pinned by URL and
# SHA-256 and downloaded once at configure time; the host build hands the
# folder to the win64 build (MFBD_KLU_SOURCE_DIR). Including this file
# fetches; mfbd_add_klu() defines the library; mfbd_stage_licenses(DIR)
# puts the licences of what the FMU binaries link into DIR, which the
# packer copies into every FMU as documentation/licenses.
#
# MFBD_SYSTEM_KLU=ON links the system's shared KLU instead (Debian's
# libsuitesparse-dev, SuiteSparse 5.12), as the linux64 binary did before
# issue 19: only for benchmarks/platform_speed.py's "before" binary, which
# needs libklu.so.1 at run time and is never packed.
include_guard(GLOBAL)
option(MFBD_SYSTEM_KLU "Link the system's shared KLU (pre-portability benchmarks only)" OFF)
if(MFBD_SYSTEM_KLU AND NOT MFBD_FMU_ONLY)
  message(FATAL_ERROR "MFBD_SYSTEM_KLU=ON builds an FMU binary alone (add -DMFBD_FMU_ONLY=ON): "
                      "packed FMUs carry the pinned KLU and its licences")
endif()
set(MFBD_KLU_SOURCE_DIR "" CACHE PATH "Folder of the klujax 0.2.0 sdist (default: downloaded)")
if(NOT MFBD_KLU_SOURCE_DIR AND NOT MFBD_SYSTEM_KLU)
  include(FetchContent)
  FetchContent_Declare(klujax_sdist
    URL https://files.pythonhosted.org/packages/a5/50/10d36cb6e80b9dd392492af925d56b8fc14fe9c02b3cb5975845e96708c5/klujax-0.2.0.tar.gz
    URL_HASH SHA256=0faa4b343756d3be2eeffd19d9ff6b25788ef8646fd1938422cc948291de1aae
    DOWNLOAD_EXTRACT_TIMESTAMP TRUE)
  FetchContent_GetProperties(klujax_sdist)
  if(NOT klujax_sdist_POPULATED)
    FetchContent_Populate(klujax_sdist)
  endif()
  set(MFBD_KLU_SOURCE_DIR "${klujax_sdist_SOURCE_DIR}" CACHE PATH "Folder of the klujax 0.2.0 sdist" FORCE)
endif()

function(mfbd_add_klu)
  if(MFBD_SYSTEM_KLU)
    find_path(MFBD_SYSTEM_KLU_INCLUDE_DIR klu.h PATH_SUFFIXES suitesparse REQUIRED)
    find_library(MFBD_SYSTEM_KLU_LIBRARY klu REQUIRED)
    add_library(SuiteSparse::KLU INTERFACE IMPORTED GLOBAL)
    target_include_directories(SuiteSparse::KLU SYSTEM INTERFACE ${MFBD_SYSTEM_KLU_INCLUDE_DIR})
    target_link_libraries(SuiteSparse::KLU INTERFACE ${MFBD_SYSTEM_KLU_LIBRARY})
    return()
  endif()
  set(root "${MFBD_KLU_SOURCE_DIR}/suitesparse")
  # The 32-bit-index real routines only (the _l, _z and _zl files are the
  # 64-bit-index and complex variants).
  set(sources "${root}/SuiteSparse_config/SuiteSparse_config.c" "${root}/COLAMD/Source/colamd.c")
  foreach(part AMD:amd BTF:btf KLU:klu)
    string(REPLACE ":" ";" part ${part})
    list(GET part 0 dir)
    list(GET part 1 prefix)
    file(GLOB found "${root}/${dir}/Source/${prefix}*.c")
    list(FILTER found EXCLUDE REGEX "/${prefix}_(l|z|zl)[_.0-9]")
    list(APPEND sources ${found})
  endforeach()
  add_library(mfbd_klu STATIC ${sources})
  target_include_directories(mfbd_klu SYSTEM PUBLIC
    ${root}/SuiteSparse_config ${root}/AMD/Include ${root}/COLAMD/Include
    ${root}/BTF/Include ${root}/KLU/Include)
  # Third-party C: its warnings are not ours; no printing, no timer.
  target_compile_options(mfbd_klu PRIVATE -w)
  target_compile_definitions(mfbd_klu PRIVATE NPRINT NTIMER)
  add_library(SuiteSparse::KLU ALIAS mfbd_klu)
endfunction()

# KLU and BTF are LGPL-2.1-or-later, AMD, COLAMD and SuiteSparse_config
# BSD-3-Clause: our note (fmu_src/licenses/README.txt), SuiteSparse's
# notices from the source, and the LGPL's text (Debian's common licences).
function(mfbd_stage_licenses dir)
  find_file(MFBD_LGPL_2_1 LGPL-2.1 PATHS /usr/share/common-licenses NO_DEFAULT_PATH REQUIRED)
  configure_file(${CMAKE_SOURCE_DIR}/fmu_src/licenses/README.txt ${dir}/README.txt COPYONLY)
  configure_file(${MFBD_KLU_SOURCE_DIR}/suitesparse/LICENSE.txt ${dir}/SuiteSparse-LICENSE.txt COPYONLY)
  configure_file(${MFBD_LGPL_2_1} ${dir}/LGPL-2.1.txt COPYONLY)
endfunction()

# The win64 build (toolchain cmake/mingw-w64-x86_64.cmake), included by
# CMakeLists.txt. Eigen and nlohmann/json are header-only: their host
# headers are used through links in the build folder, never the host's
# /usr/include as a whole (its C library headers are not Windows').
# KLU is built from source (cmake/klu.cmake), as on linux64.
set(host_headers "${CMAKE_BINARY_DIR}/host_headers")
file(MAKE_DIRECTORY ${host_headers})
foreach(header eigen3/Eigen nlohmann)
  string(MAKE_C_IDENTIFIER ${header} id)
  find_path(MFBD_HOST_${id} ${header} PATHS /usr/include /usr/local/include NO_DEFAULT_PATH
            NO_CMAKE_FIND_ROOT_PATH REQUIRED)
  get_filename_component(name ${header} NAME)
  file(CREATE_LINK "${MFBD_HOST_${id}}/${header}" "${host_headers}/${name}" SYMBOLIC)
endforeach()
add_library(Eigen3::Eigen INTERFACE IMPORTED)
target_include_directories(Eigen3::Eigen INTERFACE ${host_headers})
add_library(nlohmann_json::nlohmann_json INTERFACE IMPORTED)
target_include_directories(nlohmann_json::nlohmann_json INTERFACE ${host_headers})
# libstdc++, libgcc and winpthread linked in; fmi2 functions exported by
# their dllexport (fmi2Functions.h), nothing else.
add_link_options(-static)
# GCC does not align the stack to 32 bytes on Windows x64, where the AVX2
# beam kernel spills vectors: unaligned moves for those spills.
add_compile_options(-Wa,-muse-unaligned-vector-move)

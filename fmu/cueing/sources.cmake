# The cueing FMU's model-predictive cueing (mpc.c) builds in, besides fmu/cueing/:
# - the platform's inverse kinematics, fmu/mechanics/platform.c (one implementation: the mechanics');
# - the guard (guard.c): the platform's envelope, fmu/mechanics/envelope.c, and the guard's stepping,
#   fmu/common/motion_guard.c (one implementation: the step kernel's);
# - DAQP 0.11.0 (Arnstrom, Bemporad and Axehill 2022; MIT licence, shipped in sources/ as
#   DAQP_LICENSE), the dual active-set QP solver: the C sources its PyPI sdist carries (csrc/),
#   fetched once per build folder and checked by their hash. Its own warnings are not ours to fix:
#   it compiles without -Wall/-Wextra/-Wpedantic.
include(FetchContent)
FetchContent_Declare(daqp
  URL https://files.pythonhosted.org/packages/c2/5d/6ae925a74c02e68a1356a49261dc42af98fa1cda75c16428e49cb7b1f0f9/daqp-0.11.0.tar.gz
  URL_HASH SHA256=2f27baf18d2acca14186498e651b34e0bed455627e777d3fd8ba655e7e40f920
  DOWNLOAD_EXTRACT_TIMESTAMP ON)
FetchContent_MakeAvailable(daqp)
file(GLOB daqp_sources "${daqp_SOURCE_DIR}/csrc/src/*.c")
file(GLOB daqp_headers "${daqp_SOURCE_DIR}/csrc/include/*.h")
if(CMAKE_C_COMPILER_ID MATCHES "GNU|Clang")
  set_source_files_properties(${daqp_sources} PROPERTIES COMPILE_OPTIONS "-w")
endif()
configure_file("${daqp_SOURCE_DIR}/LICENSE" "${generated_dir}/DAQP_LICENSE" COPYONLY)
list(APPEND model_sources "${CMAKE_SOURCE_DIR}/fmu/mechanics/platform.c" "${CMAKE_SOURCE_DIR}/fmu/mechanics/envelope.c"
     "${CMAKE_SOURCE_DIR}/fmu/common/motion_guard.c" ${daqp_sources})
list(APPEND model_headers "${CMAKE_SOURCE_DIR}/fmu/mechanics/platform.h" "${CMAKE_SOURCE_DIR}/fmu/mechanics/envelope.h"
     "${CMAKE_SOURCE_DIR}/fmu/common/motion_guard.h" ${daqp_headers} "${generated_dir}/DAQP_LICENSE")
list(APPEND include_dirs "${CMAKE_SOURCE_DIR}/fmu/mechanics" "${daqp_SOURCE_DIR}/csrc/include")

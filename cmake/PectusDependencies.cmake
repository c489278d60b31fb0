# Every dependency as an imported target, found with a version. Debian 12 (bookworm) versions are the floor.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(OpenMP REQUIRED COMPONENTS CXX)
find_package(Threads REQUIRED)

if(PECTUS_BUILD_TESTS)
  find_package(GTest 1.12 REQUIRED)
  include(GoogleTest)
endif()

# liblzf expands PCD's binary_compressed blocks (shape/io/pcd_io.cc). Debian's liblzf-dev puts lzf.h in
# include/liblzf/; find it by hand and make an imported target, so that every build (core-only too) has it.
find_path(LZF_INCLUDE_DIR lzf.h PATH_SUFFIXES liblzf)
find_library(LZF_LIBRARY lzf)
if(NOT LZF_INCLUDE_DIR OR NOT LZF_LIBRARY)
  message(FATAL_ERROR "liblzf not found (lzf.h: ${LZF_INCLUDE_DIR}, library: ${LZF_LIBRARY}): the PCD reader "
                      "needs it; install Debian's liblzf-dev (scripts/bootstrap does)")
endif()
if(NOT TARGET LZF::lzf)
  add_library(LZF::lzf UNKNOWN IMPORTED)
  set_target_properties(LZF::lzf PROPERTIES IMPORTED_LOCATION ${LZF_LIBRARY}
                        INTERFACE_INCLUDE_DIRECTORIES ${LZF_INCLUDE_DIR})
endif()

if(PECTUS_CORE_ONLY)
  return()
endif()

find_package(CLI11 2.1 REQUIRED)
# MPI (Open MPI from Debian, installed by scripts/bootstrap): `mpirun -n N pectus ...` farms the subjects
# out over ranks (docs/cluster.md). Optional: without it `pectus` is the same serial tool.
find_package(MPI 3.0 COMPONENTS CXX)
set(PECTUS_HAVE_MPI ${MPI_CXX_FOUND})
if(PECTUS_HAVE_MPI)
  message(STATUS "pectus: MPI found (${MPIEXEC_EXECUTABLE}); `mpirun -n N pectus ...` shares subjects out")
else()
  message(STATUS "pectus: MPI not found; `pectus` runs on one machine only (install libopenmpi-dev)")
endif()
find_package(nanoflann 1.4 REQUIRED)
find_package(Ceres 2.1 REQUIRED)
find_package(OpenCV 4.6 REQUIRED COMPONENTS core imgproc)
find_package(PNG 1.6 REQUIRED)
find_package(HDF5 1.10 REQUIRED COMPONENTS C)
find_package(CGAL 5.5 REQUIRED)
if(PECTUS_BUILD_BENCHMARKS)
  find_package(benchmark 1.7 REQUIRED)
endif()

# PCL's own config sets directory-wide include paths and definitions; wrap just the modules we use into
# one imported target so that only the adaptor files that include PCL see it.
find_package(PCL 1.13 REQUIRED COMPONENTS common io kdtree search features registration surface filters)
if(NOT TARGET pectus::pcl)
  add_library(pectus_pcl INTERFACE)
  add_library(pectus::pcl ALIAS pectus_pcl)
  target_include_directories(pectus_pcl SYSTEM INTERFACE ${PCL_INCLUDE_DIRS})
  target_link_libraries(pectus_pcl INTERFACE ${PCL_LIBRARIES})
  target_compile_definitions(pectus_pcl INTERFACE ${PCL_DEFINITIONS})
endif()

# CHOLMOD (SuiteSparse) has no CMake config in Debian 12; find it and make an imported target.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
if(NOT TARGET SuiteSparse::CHOLMOD)
  add_library(SuiteSparse::CHOLMOD UNKNOWN IMPORTED)
  set_target_properties(SuiteSparse::CHOLMOD PROPERTIES IMPORTED_LOCATION ${CHOLMOD_LIBRARY}
                        INTERFACE_INCLUDE_DIRECTORIES ${CHOLMOD_INCLUDE_DIR})
endif()

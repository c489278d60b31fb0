# Every dependency as an imported target, found with a version. Debian 12 (bookworm) versions are the floor.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(OpenMP REQUIRED COMPONENTS CXX)
find_package(Threads REQUIRED)

if(PECTUS_BUILD_TESTS)
  find_package(GTest 1.12 REQUIRED)
  include(GoogleTest)
endif()

if(PECTUS_CORE_ONLY)
  return()
endif()

find_package(CLI11 2.1 REQUIRED)
find_package(nanoflann 1.4 REQUIRED)
find_package(Ceres 2.1 REQUIRED)
find_package(OpenCV 4.6 REQUIRED COMPONENTS core imgproc imgcodecs)
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

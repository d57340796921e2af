# FindOpenVDB: OpenVDB (Debian: libopenvdb-dev 10). Debian's own FindOpenVDB.cmake asks for
# Boost.Iostreams, which the package does not depend on; this one needs only what the headers
# include: TBB and Imath (both ship CMake configs). Defines OpenVDB_FOUND and the imported
# target OpenVDB::openvdb.
find_path(OpenVDB_INCLUDE_DIR openvdb/openvdb.h)
find_library(OpenVDB_LIBRARY NAMES openvdb)
find_package(TBB CONFIG QUIET)
find_package(Imath CONFIG QUIET)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenVDB REQUIRED_VARS OpenVDB_LIBRARY OpenVDB_INCLUDE_DIR TBB_FOUND Imath_FOUND)
if(OpenVDB_FOUND AND NOT TARGET OpenVDB::openvdb)
  add_library(OpenVDB::openvdb UNKNOWN IMPORTED)
  set_target_properties(OpenVDB::openvdb PROPERTIES
    IMPORTED_LOCATION "${OpenVDB_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OpenVDB_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "TBB::tbb;Imath::Imath")
endif()
mark_as_advanced(OpenVDB_INCLUDE_DIR OpenVDB_LIBRARY)

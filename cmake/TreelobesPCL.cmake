# Imported targets PCL::<module> for the PCL modules treelobes uses.
#
# Debian 12's PCLConfig.cmake drags in VTK, whose exported targets reference MPI::MPI_C and
# fail to configure without an MPI toolchain; we only need a few PCL libraries (which carry
# their own runtime dependencies), so we locate their headers and shared objects directly.
find_path(PCL_INCLUDE_DIR pcl/point_cloud.h PATH_SUFFIXES pcl-1.13 pcl-1.12 REQUIRED)
find_package(Boost REQUIRED)

foreach(module common io kdtree search octree filters sample_consensus segmentation features)
  find_library(PCL_${module}_LIBRARY pcl_${module} REQUIRED)
  add_library(PCL::${module} SHARED IMPORTED)
  set_target_properties(PCL::${module} PROPERTIES
    IMPORTED_LOCATION "${PCL_${module}_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${PCL_INCLUDE_DIR};${Boost_INCLUDE_DIRS}"
    INTERFACE_LINK_LIBRARIES "Eigen3::Eigen")
endforeach()

# Script mode: cmake -DROOT=<source tree> [-DSTAGES="a;b"] -P cmake/check_layering.cmake
# Checks the include layering of every stage folder of ROOT (default: all of TREELOBES_STAGES).
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/TreelobesLayering.cmake)
if(NOT DEFINED STAGES)
  set(STAGES ${TREELOBES_STAGES})
endif()
foreach(stage ${STAGES})
  treelobes_check_layering("${ROOT}" ${stage})
endforeach()
message(STATUS "layering: ${STAGES} include only what they may")

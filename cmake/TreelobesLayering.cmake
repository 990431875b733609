# The folder layering of treelobes, stated once. Data flows one way (DESIGN.md): core ->
# geometry -> the stages -> apps. TREELOBES_DEPENDS_<stage> lists what each folder may include
# besides itself: folders, or single headers for a narrow dependency. Checked at configure time
# (top-level CMakeLists.txt) and by the `layering` test (cmake/check_layering.cmake), so a stage
# that includes a header of a folder it must not use fails the build and the suite.
set(TREELOBES_DEPENDS_core "")
set(TREELOBES_DEPENDS_geometry core)
set(TREELOBES_DEPENDS_config core)
set(TREELOBES_DEPENDS_lsystem core)
set(TREELOBES_DEPENDS_encode core)
set(TREELOBES_DEPENDS_render core)
set(TREELOBES_DEPENDS_reconstruct core geometry)
set(TREELOBES_DEPENDS_segment core geometry render)
set(TREELOBES_DEPENDS_synth core geometry config)
# lobes and classify start from a first reconstruction of the tree: its entry points only.
set(TREELOBES_DEPENDS_lobes core geometry config lsystem reconstruct/reconstruct_tree.hpp)
set(TREELOBES_DEPENDS_classify core geometry render
    reconstruct/reconstruct_tree.hpp reconstruct/preprocess.hpp reconstruct/skeleton.hpp reconstruct/allometry.hpp)
# export reads our tree files (encode, lobes) and writes them for other tools (render: PNG
# textures embedded in glTF).
set(TREELOBES_DEPENDS_export core geometry encode lobes render)
# forestry runs every tree of a tile through the single-tree stages: their entry points.
set(TREELOBES_DEPENDS_forestry core geometry encode lobes classify reconstruct/reconstruct_tree.hpp)
# survey: many tiles (their list and shards, completion markers, memory estimate, retiling, merging).
set(TREELOBES_DEPENDS_survey core encode)
set(TREELOBES_DEPENDS_apps core geometry config lsystem encode reconstruct segment lobes classify forestry survey synth render export)
# Build order of the stage folders (each one CMake library target treelobes_<stage>).
set(TREELOBES_STAGES core geometry config lsystem encode render reconstruct segment synth lobes classify forestry survey export apps)

# Fails with one message naming the file and the include when a source of `stage` (a folder of
# `root`) includes "<folder>/..." that is neither the stage itself nor in its list. A folder with
# no list fails too: a new stage declares what it uses before it uses it.
function(treelobes_check_layering root stage)
  if(NOT DEFINED TREELOBES_DEPENDS_${stage})
    message(FATAL_ERROR "layering: stage '${stage}' has no TREELOBES_DEPENDS_${stage} list in cmake/TreelobesLayering.cmake")
  endif()
  set(allowed ${TREELOBES_DEPENDS_${stage}})
  file(GLOB_RECURSE sources "${root}/${stage}/*.cpp" "${root}/${stage}/*.hpp")
  foreach(source ${sources})
    file(STRINGS "${source}" includes REGEX "^[ \t]*#[ \t]*include[ \t]+\"[A-Za-z0-9_]+/[^\"]+\"")
    foreach(line ${includes})
      string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]+\"(([A-Za-z0-9_]+)/[^\"]+)\".*$" "\\1;\\2" parsed "${line}")
      list(GET parsed 0 header)
      list(GET parsed 1 folder)
      if(folder STREQUAL stage OR folder IN_LIST allowed OR header IN_LIST allowed)
        continue()
      endif()
      file(RELATIVE_PATH where "${root}" "${source}")
      message(FATAL_ERROR "layering: ${where} includes \"${header}\", but ${stage}/ may use only: ${allowed} "
                          "(TREELOBES_DEPENDS_${stage} in cmake/TreelobesLayering.cmake)")
    endforeach()
  endforeach()
endfunction()

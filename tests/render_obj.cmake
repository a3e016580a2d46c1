# examples/render_obj: an OBJ written here (a tetrahedron standing on its face) and, with no
# file, the generated sphere, each rendered to a small EXR; the file must exist and hold lit
# pixels (exr_stats reads it back: R has non-zero values and a maximum above the sky's 0.04).
# Run with -DEXE=<render_obj> -DSTATS=<exr_stats> -DDIR=<scratch folder> -P render_obj.cmake.
file(WRITE ${DIR}/render_obj_tetra.obj "v 0 0 0\nv 1 0 0\nv 0 0 -1\nv 0.3 1 -0.3\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n")
foreach(case IN ITEMS tetra sphere)
  set(out ${DIR}/render_obj_${case}.exr)
  file(REMOVE ${out})
  set(mesh ${DIR}/render_obj_${case}.obj)  # render_obj_sphere.obj does not exist: the generated sphere
  execute_process(COMMAND ${EXE} ${mesh} ${out} 32 RESULT_VARIABLE rc OUTPUT_VARIABLE log ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT EXISTS ${out})
    message(FATAL_ERROR "render_obj ${case} failed (${rc}): ${log} ${err}")
  endif()
  execute_process(COMMAND ${STATS} ${out} RESULT_VARIABLE rc OUTPUT_VARIABLE stats ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT stats MATCHES "32 x 32\n" OR NOT stats MATCHES "channel R min [^ ]+ max ([0-9.e+-]+) mean [^ ]+ nonzero ([0-9]+)")
    message(FATAL_ERROR "cannot read ${out} back: ${stats} ${err}")
  endif()
  if(NOT CMAKE_MATCH_2 GREATER 0 OR NOT CMAKE_MATCH_1 GREATER 0.1)
    message(FATAL_ERROR "${out} has no lit pixels: ${stats}")
  endif()
  message(STATUS "${case}: ${log}R max ${CMAKE_MATCH_1}, ${CMAKE_MATCH_2} non-zero pixels")
endforeach()

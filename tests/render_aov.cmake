# glint-render --aov: the first-hit layers and the header attributes in the EXR, read back by
# io/exr.hpp (exr_stats), by OpenEXR's own exrheader where the openexr tools are installed,
# and by tools/exr.py where a Python 3 with numpy is (the file as glint writes it, ZIP, and
# rewritten by OpenEXR with PIZ, its default compression). Run with -DEXE=<glint-render>
# -DSTATS=<exr_stats> -DDIR=<scratch folder> -DVERSION=<glint's> [-DPYTHON=<python3 with numpy>
# -DEXR_PY_TEST=<tests/exr_py_check.py>] -P render_aov.cmake.
set(out ${DIR}/aov_cornell.exr)
file(REMOVE ${out})
execute_process(COMMAND ${EXE} --scene cornell --size 24 --spp 2 --threads 1 --aov --out ${out}
                RESULT_VARIABLE rc OUTPUT_VARIABLE log ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${out})
  message(FATAL_ERROR "glint-render --aov failed (${rc}): ${log} ${err}")
endif()
execute_process(COMMAND ${STATS} ${out} ${DIR}/aov_cornell_piz.exr piz RESULT_VARIABLE rc OUTPUT_VARIABLE stats
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "exr_stats cannot read ${out}: ${err}")
endif()
foreach(want "channel albedo.R " "channel albedo.G " "channel albedo.B " "channel normal.X " "channel normal.Y "
             "channel normal.Z " "channel depth.Z " "channel variance.R " "attribute glint:spp = 2\n"
             "attribute glint:version = ${VERSION}\n" "attribute glint:render_seconds = [0-9]"
             "attribute glint:policies = integrator=path accel=bvh8 roulette=throughput direct=mis")
  if(NOT stats MATCHES "${want}")
    message(FATAL_ERROR "${out} lacks '${want}':\n${stats}")
  endif()
endforeach()
# Depth positive (+inf where every ray of a pixel leaves the open box), albedo within [0, 1].
if(NOT stats MATCHES "channel depth.Z min [0-9.]+ max " OR NOT stats MATCHES "channel albedo.R min 0?[.0-9e-]* max (0[.][0-9]+|1) ")
  message(FATAL_ERROR "implausible layers:\n${stats}")
endif()
find_program(EXRHEADER exrheader)
if(EXRHEADER)
  foreach(file ${out} ${DIR}/aov_cornell_piz.exr)
    execute_process(COMMAND ${EXRHEADER} ${file} RESULT_VARIABLE rc OUTPUT_VARIABLE header)
    if(NOT rc EQUAL 0 OR NOT header MATCHES "albedo.R, 32-bit floating-point" OR NOT header MATCHES "depth.Z, 32-bit"
       OR NOT header MATCHES "glint:spp \\(type int\\): 2" OR NOT header MATCHES "glint:version \\(type string\\)")
      message(FATAL_ERROR "exrheader ${file}:\n${header}")
    endif()
  endforeach()
  if(NOT header MATCHES "compression \\(type compression\\): piz")
    message(FATAL_ERROR "the rewritten file is not PIZ:\n${header}")
  endif()
  message(STATUS "exrheader (OpenEXR) reads the layers and attributes of both files")
else()
  message(STATUS "exrheader not installed (Debian openexr): OpenEXR's tools not run")
endif()
if(PYTHON)
  execute_process(COMMAND ${PYTHON} ${EXR_PY_TEST} ${out} ${DIR}/aov_cornell_piz.exr ${STATS} ${DIR} RESULT_VARIABLE rc
                  OUTPUT_VARIABLE py ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "tools/exr.py: ${py} ${err}")
  endif()
  message(STATUS "${py}")
else()
  message(STATUS "no Python 3 with numpy: tools/exr.py not run")
endif()

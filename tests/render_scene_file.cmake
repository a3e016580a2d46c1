# glint-render's scene files: a built-in scene exported with --export-scene and rendered with
# --scene-file gives the same EXR, byte for byte, as the built-in scene rendered directly, and
# both print the camera in the flags' syntax. Run with -DEXE=<glint-render> -DSTATS=<exr_stats>
# -DDIR=<scratch folder> -P render_scene_file.cmake.
set(common --spp 2 --threads 1 --max-depth 16)
execute_process(COMMAND ${EXE} --scene cornell-glossy --width 24 --height 16 --export-scene ${DIR}/sf_scene.json
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "--export-scene failed: ${err}")
endif()
execute_process(COMMAND ${EXE} --scene cornell-glossy --width 24 --height 16 ${common} --out ${DIR}/sf_direct.exr
                RESULT_VARIABLE rc1 ERROR_VARIABLE err1)
execute_process(COMMAND ${EXE} --scene-file ${DIR}/sf_scene.json ${common} --out ${DIR}/sf_file.exr
                RESULT_VARIABLE rc2 ERROR_VARIABLE err2)
if(NOT rc1 EQUAL 0 OR NOT rc2 EQUAL 0)
  message(FATAL_ERROR "render failed: ${err1} ${err2}")
endif()
foreach(err IN ITEMS "${err1}" "${err2}")
  if(NOT err MATCHES "camera: --eye [-0-9.e]+,[-0-9.e]+,[-0-9.e]+ --look-at [^ ]+ --up [^ ]+ --fov [0-9.]+")
    message(FATAL_ERROR "no camera line in: ${err}")
  endif()
endforeach()
# The pixels bit for bit (exr_stats hashes each channel's floats) and the header's attributes
# but the render time.
foreach(f direct file)
  execute_process(COMMAND ${STATS} ${DIR}/sf_${f}.exr RESULT_VARIABLE rc OUTPUT_VARIABLE stats_${f})
  string(REGEX REPLACE "attribute glint:render_seconds = [^\n]*\n" "" stats_${f} "${stats_${f}}")
endforeach()
if(NOT stats_direct STREQUAL stats_file OR NOT stats_direct MATCHES "channel R .* hash ")
  message(FATAL_ERROR "the scene file renders differently from the built-in scene:\n${stats_direct}\n${stats_file}")
endif()
message(STATUS "--scene-file renders the exported scene bit for bit as the built-in one")

# A glTF file (one triangle, its buffer a base64 data URI; no camera, no light): framed as
# --mesh frames an OBJ, lit by the sky, and the camera it chose printed.
file(WRITE ${DIR}/sf_triangle.gltf [=[{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
  "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": 3}]}]=])
execute_process(COMMAND ${EXE} --scene-file ${DIR}/sf_triangle.gltf --size 8 --spp 1 --threads 1 --out ${DIR}/sf_triangle.exr
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "rendered .*sf_triangle.gltf" OR NOT err MATCHES "camera: --eye .* --fov 40.1070")
  message(FATAL_ERROR "the glTF scene did not render as expected (${rc}): ${out} ${err}")
endif()
message(STATUS "--scene-file renders a glTF: ${err}")

# Installs glint from the build tree into a scratch prefix, then configures, builds and runs
# tests/consumer against it with find_package(glint CONFIG REQUIRED COMPONENTS io); builds
# its io program again with the pkg-config file's flags (when pkg-config is installed); and
# checks that add_subdirectory(glint) adds no build-only target to a parent project.
# Variables: BUILD_DIR (glint's build tree), SOURCE_DIR (tests/consumer), WORK_DIR.
file(REMOVE_RECURSE ${WORK_DIR})
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}")
  endif()
endfunction()
function(run_in dir)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY ${dir} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}")
  endif()
endfunction()
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/consumer)
run_in(${WORK_DIR}/build ${WORK_DIR}/build/consumer_io)

find_program(PKG_CONFIG pkg-config)
if(PKG_CONFIG)
  set(ENV{PKG_CONFIG_PATH} ${WORK_DIR}/prefix/share/pkgconfig)
  execute_process(COMMAND ${PKG_CONFIG} --cflags --libs glint-io OUTPUT_VARIABLE flags
                  OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pkg-config --cflags --libs glint-io failed")
  endif()
  message(STATUS "pkg-config glint-io: ${flags}")
  if(flags MATCHES "-std=")
    message(FATAL_ERROR "the .pc files must leave the language standard to the user (C++20 or later): ${flags}")
  endif()
  separate_arguments(flags UNIX_COMMAND "${flags}")
  run(c++ -std=c++20 ${SOURCE_DIR}/io.cpp ${flags} -o ${WORK_DIR}/consumer_pkgconfig)
  run_in(${WORK_DIR} ${WORK_DIR}/consumer_pkgconfig)
else()
  message(STATUS "pkg-config not installed: the .pc files are not checked")
endif()

# add_subdirectory: the parent sees glint::glint and glint::io, and no glint_build.
file(MAKE_DIRECTORY ${WORK_DIR}/parent)
file(WRITE ${WORK_DIR}/parent/CMakeLists.txt "cmake_minimum_required(VERSION 3.20)
project(parent LANGUAGES CXX)
add_subdirectory(${SOURCE_DIR}/../.. glint)
foreach(t glint::glint glint::io)
  if(NOT TARGET \${t})
    message(FATAL_ERROR \"add_subdirectory(glint) did not define \${t}\")
  endif()
endforeach()
if(TARGET glint_build)
  message(FATAL_ERROR \"add_subdirectory(glint) leaked the build-only target glint_build\")
endif()
")
run(${CMAKE_COMMAND} -S ${WORK_DIR}/parent -B ${WORK_DIR}/parent/build)

# A component glint does not have (the wrong case included) fails naming it.
file(MAKE_DIRECTORY ${WORK_DIR}/wrong_component)
file(WRITE ${WORK_DIR}/wrong_component/CMakeLists.txt "cmake_minimum_required(VERSION 3.20)
project(wrong_component LANGUAGES CXX)
find_package(glint CONFIG REQUIRED COMPONENTS IO)
")
execute_process(COMMAND ${CMAKE_COMMAND} -S ${WORK_DIR}/wrong_component -B ${WORK_DIR}/wrong_component/build
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT "${out}${err}" MATCHES "unknown component 'IO'")
  message(FATAL_ERROR "find_package(glint COMPONENTS IO) should fail naming 'IO', got ${rc}: ${out}${err}")
endif()

# glint-render is installed with the package (where the examples were built).
if(EXISTS ${BUILD_DIR}/examples/glint-render)
  run(${WORK_DIR}/prefix/bin/glint-render --version)
endif()

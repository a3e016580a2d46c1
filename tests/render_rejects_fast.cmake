# glint-render must reject an unknown policy name before it reads any file: run with
# -DEXE=<glint-render> -DDIR=<scratch folder> -P render_rejects_fast.cmake. --mesh names a FIFO
# that nobody writes, so a glint-render that opened the mesh would block on it (and the 10 s
# timeout below fails the test); the error must name the unknown roulette and the whole run
# take less than 0.1 s of wall time.
set(fifo ${DIR}/never_written.obj)
file(REMOVE ${fifo})
execute_process(COMMAND mkfifo ${fifo} RESULT_VARIABLE made)
if(NOT made EQUAL 0)
  message(FATAL_ERROR "mkfifo ${fifo} failed")
endif()
string(TIMESTAMP t0 "%s%f")
execute_process(COMMAND ${EXE} --mesh ${fifo} --roulette nosuch --out ${DIR}/never_written.exr
                RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_VARIABLE out TIMEOUT 10)
string(TIMESTAMP t1 "%s%f")
file(REMOVE ${fifo})
math(EXPR us "${t1} - ${t0}")
message(STATUS "glint-render rejected the name in ${us} us: ${err}")
if(rc EQUAL 0 OR NOT err MATCHES "unknown roulette 'nosuch' \\(throughput, ")
  message(FATAL_ERROR "expected the unknown roulette's error, got status ${rc}: ${err}${out}")
endif()
if(us GREATER 100000)
  message(FATAL_ERROR "the unknown name took ${us} us to reject, above 0.1 s")
endif()

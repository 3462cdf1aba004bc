# ctest fixture: writes the synthetic jaw with `toothfuse demo --out OUT` (OUT/ios.ply and
# OUT/cbct.ply). Until the CLI's demo command is merged, it writes nothing; then this falls back
# to make_test_jaw.py (same format) with a warning. TODO(lead): drop the fallback once
# `toothfuse demo` lands on main.
# cmake -DTOOTHFUSE=<exe> -DOUT=<dir> -DPYTHON=<python3> -DFALLBACK=<script> -P make_demo.cmake
file(REMOVE_RECURSE "${OUT}")
file(MAKE_DIRECTORY "${OUT}")
execute_process(COMMAND "${TOOTHFUSE}" demo --out "${OUT}" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "`${TOOTHFUSE} demo --out ${OUT}` failed (${rc})")
endif()
if(NOT EXISTS "${OUT}/ios.ply" OR NOT EXISTS "${OUT}/cbct.ply")
  if(NOT PYTHON OR NOT EXISTS "${FALLBACK}")
    message(FATAL_ERROR "`toothfuse demo --out ${OUT}` wrote no ios.ply/cbct.ply")
  endif()
  message(WARNING "`toothfuse demo` wrote no ios.ply/cbct.ply (CLI not merged yet?); "
                  "falling back to ${FALLBACK}")
  execute_process(COMMAND "${PYTHON}" "${FALLBACK}" --out "${OUT}" RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${FALLBACK} failed (${rc})")
  endif()
endif()
message(STATUS "synthetic jaw in ${OUT}")

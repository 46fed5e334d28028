# Runs one example program for ctest and checks both its exit code and its output (ctest's
# PASS_REGULAR_EXPRESSION alone would ignore the exit code). Arguments: -DCOMMAND=<program;args> (a list),
# -DEXPECT=<regular expression the standard output must match>. The examples run on the test device:
# $STEX_TEST_DEVICE (tests/test_device.h), passed as their DEVICE argument when set.
if(NOT DEFINED COMMAND OR NOT DEFINED EXPECT)
  message(FATAL_ERROR "run_example.cmake needs -DCOMMAND=... and -DEXPECT=...")
endif()
if(NOT "$ENV{STEX_TEST_DEVICE}" STREQUAL "")
  list(APPEND COMMAND "$ENV{STEX_TEST_DEVICE}")
endif()
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}")
if(NOT err STREQUAL "")
  message("stderr:\n${err}")
endif()
if(NOT rc STREQUAL "0")
  message(FATAL_ERROR "the example exited with status '${rc}' (expected 0)")
endif()
if(NOT out MATCHES "${EXPECT}")
  message(FATAL_ERROR "the example's output does not match '${EXPECT}'")
endif()

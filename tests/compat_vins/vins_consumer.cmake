# compat.vins_consumer: the VINS consumer of tests/package/vins, built in the
# tree, run on a VINS binary vocabulary of the golden words that the CLI
# writes (as `binbow convert --to vins` makes brief_k10L6.bin files).
#   cmake -DCLI=... -DCONSUMER=... -DSOURCE_DIR=... -DWORK_DIR=... -P vins_consumer.cmake
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(vocabulary ${WORK_DIR}/brief_k10L6.bin)
execute_process(COMMAND ${CLI} convert ${SOURCE_DIR}/data/vocab/orb_default.bbw ${vocabulary} --to vins
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc)
  message(FATAL_ERROR "binbow convert --to vins failed (${rc}):\n${out}\n${err}")
endif()
execute_process(COMMAND ${CONSUMER} ${vocabulary} ${SOURCE_DIR}/tests/compat/dbow2_golden.txt
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc OR NOT out MATCHES "numbers equal to DBoW2's: [1-9][0-9]*, mismatches: 0, newest entry returned: [1-9]")
  message(FATAL_ERROR "the VINS consumer failed (${rc}):\n${out}\n${err}")
endif()
message(STATUS "${out}")

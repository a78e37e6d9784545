# test_hard_cases: every check of `hard_cases --markdown` passes (exit 0), and docs/stability.md
# holds exactly its output between the lines <!-- hard-cases:begin --> and <!-- hard-cases:end -->.
# cmake -DEXE=path/to/hard_cases -DDOC=docs/stability.md -P hard_cases_table.cmake
execute_process(COMMAND ${EXE} --markdown OUTPUT_VARIABLE table ERROR_VARIABLE log
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${EXE} --markdown exited with ${rc}:\n${log}")
endif()
file(READ ${DOC} doc)
# The markers are whole lines (the prose may quote them inline).
set(begin "\n<!-- hard-cases:begin -->\n")
set(end "\n<!-- hard-cases:end -->\n")
string(FIND "${doc}" "${begin}" b)
if(b EQUAL -1)
  message(FATAL_ERROR "${DOC} lacks the line <!-- hard-cases:begin -->")
endif()
string(LENGTH "${begin}" lb)
math(EXPR start "${b} + ${lb}")
string(SUBSTRING "${doc}" ${start} -1 rest)
# the table ends with a newline, which the end marker's leading newline is
string(FIND "${rest}" "${end}" e)
if(e EQUAL -1)
  message(FATAL_ERROR "${DOC} lacks the line <!-- hard-cases:end --> after the begin marker")
endif()
math(EXPR len "${e} + 1")
string(SUBSTRING "${rest}" 0 ${len} current)
if(NOT current STREQUAL table)
  get_filename_component(dir ${EXE} DIRECTORY)
  file(WRITE ${dir}/hard_cases_expected.md "${table}")
  message(FATAL_ERROR "the hard-case table in ${DOC} is out of date: regenerate it with "
          "`build/tests/hard_cases --markdown` and paste the output between the markers "
          "(expected text written to ${dir}/hard_cases_expected.md)")
endif()
message(STATUS "hard-case table in ${DOC} is up to date")

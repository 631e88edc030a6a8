# cmake -DPRTLAB=... -DPLUGIN=... -DOUT=... -P run_experiments_with_plugin.cmake
#
# Runs `prtlab experiment run fig6|pareto --quick` on the tiny scene with the template plugin
# loaded and fails unless the plugin's backend (quantized8) is in each result's points.csv and
# README.md: a plugin shows up in every table without any harness edit.
file(REMOVE_RECURSE ${OUT}/results)
foreach(experiment fig6 pareto)
  execute_process(
    COMMAND ${PRTLAB} -q --no-opencl --plugin ${PLUGIN} experiment run ${experiment} --quick
            --scenes tiny-sphere-plane --out ${OUT}/results --no-plot
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${experiment}: prtlab exited with ${rc}\n${out}\n${err}")
  endif()
  foreach(f points.csv README.md)
    set(file ${OUT}/results/${experiment}-quick/${f})
    if(NOT EXISTS ${file})
      message(FATAL_ERROR "${experiment}: ${file} was not written\n${out}\n${err}")
    endif()
    file(READ ${file} text)
    string(FIND "${text}" "quantized8" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "${experiment}: the plugin's backend quantized8 is not in ${file}")
    endif()
  endforeach()
  message(STATUS "${experiment}: quantized8 is in the results")
endforeach()

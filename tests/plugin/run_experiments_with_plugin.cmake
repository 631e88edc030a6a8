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
  # The command line (with the plugin's path) is in the provenance lines and the README's
  # command row, so look only where a backend's name stands as a row of results.
  set(csv ${OUT}/results/${experiment}-quick/points.csv)
  set(md ${OUT}/results/${experiment}-quick/README.md)
  foreach(file ${csv} ${md})
    if(NOT EXISTS ${file})
      message(FATAL_ERROR "${experiment}: ${file} was not written\n${out}\n${err}")
    endif()
  endforeach()
  file(STRINGS ${csv} rows REGEX "^[^#].*,quantized8,")
  if(NOT rows)
    message(FATAL_ERROR "${experiment}: no row of ${csv} is the plugin's backend quantized8")
  endif()
  file(STRINGS ${md} table_rows REGEX "^\\| `quantized8` \\|")
  if(NOT table_rows)
    message(FATAL_ERROR "${experiment}: no table row of ${md} is the plugin's backend quantized8")
  endif()
  message(STATUS "${experiment}: quantized8 is in the results")
endforeach()

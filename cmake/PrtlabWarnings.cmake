# Warnings stay at zero with -Wall -Wextra; PRTLAB_WERROR turns them into errors (CI-style builds).
add_library(prtlab_warnings INTERFACE)
target_compile_options(prtlab_warnings INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow=local -Wno-missing-field-initializers>
  $<$<BOOL:${PRTLAB_WERROR}>:-Werror>)

# Formal proofs of the RTL (label formal, docs/formal.md): one CTest case per
# quick block of scripts/formal.sh, which proves it by BMC and k-induction and
# reaches its covers. The slow blocks run only in `make formal`.
execute_process(
  COMMAND ${CMAKE_SOURCE_DIR}/scripts/formal.sh --list quick
  OUTPUT_VARIABLE mc_formal_quick OUTPUT_STRIP_TRAILING_WHITESPACE COMMAND_ERROR_IS_FATAL ANY)
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/scripts/formal.sh)
separate_arguments(mc_formal_quick)
foreach(block IN LISTS mc_formal_quick)
  add_test(NAME formal_${block} COMMAND ${CMAKE_SOURCE_DIR}/scripts/formal.sh ${block})
  set_tests_properties(formal_${block} PROPERTIES LABELS formal TIMEOUT 900
    ENVIRONMENT FORMAL_DIR=${CMAKE_BINARY_DIR}/formal)
endforeach()

# Verilated RTL models as CMake libraries (used by sim/ and tests/).

set(MC_RTL_DIR ${CMAKE_SOURCE_DIR}/rtl)
set(MC_VERILATOR_ARGS -Wall --assert -x-assign unique -x-initial unique -O3)
set(MC_INTERP_RTL interp_core.v seg_fifo.v)
list(TRANSFORM MC_INTERP_RTL PREPEND ${MC_RTL_DIR}/)
set(MC_MOTION_RTL motion_core.v pid_core.v mul_align.v quad_decoder.v)
list(TRANSFORM MC_MOTION_RTL PREPEND ${MC_RTL_DIR}/)
list(APPEND MC_MOTION_RTL ${MC_INTERP_RTL})

# mc_verilate(<lib> TOP <module> SOURCES <files...>): a static library holding
# the Verilated model V<module>.
# PREFIX overrides the class name, PARAMS adds -G overrides, TRACE_FST builds
# in waveform dumping (off until a trace is opened).
function(mc_verilate lib)
  cmake_parse_arguments(V "TRACE_FST" "TOP;PREFIX" "SOURCES;PARAMS" ${ARGN})
  if(NOT V_PREFIX)
    set(V_PREFIX V${V_TOP})
  endif()
  set(trace)
  if(V_TRACE_FST)
    set(trace TRACE_FST)
  endif()
  add_library(${lib} STATIC)
  verilate(${lib} ${trace}
    SOURCES ${V_SOURCES}
    TOP_MODULE ${V_TOP}
    PREFIX ${V_PREFIX}
    INCLUDE_DIRS ${MC_RTL_DIR}
    VERILATOR_ARGS ${MC_VERILATOR_ARGS} ${V_PARAMS})
  # Verilator's runtime and generated code are not held to our warning flags:
  # consumers see their headers as system headers.
  target_compile_options(${lib} PRIVATE -w)
  # Verilator's runtime is not ours to fix: its FST writer
  # (gtkwave/fstapi.c) stores at unaligned addresses and shifts negative
  # values on purpose, and UBSan would stop every traced run there. These
  # libraries keep AddressSanitizer; our own code keeps UBSan as well.
  if(MC_SANITIZE OR MC_FUZZ)
    target_compile_options(${lib} PRIVATE -fno-sanitize=undefined)
  endif()
  get_target_property(vdirs ${lib} INTERFACE_INCLUDE_DIRECTORIES)
  target_include_directories(${lib} SYSTEM INTERFACE ${vdirs})
endfunction()

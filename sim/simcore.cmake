# Sim-side pieces with no plant dependency: the jitter model, the host-loop
# model and the benchmark metrics. Included from the top CMakeLists.txt until
# sim/CMakeLists.txt folds these sources into mc_sim.

# The measured histogram, embedded so that a run needs no file at run time.
set(MC_JITTER_DEFAULT ${CMAKE_SOURCE_DIR}/configs/jitter/linux_10ms.csv)
file(READ ${MC_JITTER_DEFAULT} MC_JITTER_DEFAULT_CSV)
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${MC_JITTER_DEFAULT})
configure_file(${CMAKE_SOURCE_DIR}/sim/jitter_default.hpp.in ${CMAKE_BINARY_DIR}/generated/jitter_default.hpp
               @ONLY)

add_library(mc_simcore STATIC
  ${CMAKE_SOURCE_DIR}/sim/jitter.cpp
  ${CMAKE_SOURCE_DIR}/sim/host_loop.cpp
  ${CMAKE_SOURCE_DIR}/sim/metrics.cpp
)
target_include_directories(mc_simcore PUBLIC ${CMAKE_SOURCE_DIR}/sim PRIVATE ${CMAKE_BINARY_DIR}/generated)
target_link_libraries(mc_simcore PUBLIC mc_host)
target_compile_options(mc_simcore PRIVATE ${MC_WARNINGS})

# The Grbl 1.1 front end (host/grbl/), label unit: the protocol engine on the
# dry-run machine, the settings file, the 10,000-line stream and the server
# on a real pseudo-terminal and TCP socket.

mc_gtest(test_grbl_protocol unit test_grbl_protocol.cpp)
target_link_libraries(test_grbl_protocol PRIVATE mc_grbl)

mc_gtest(test_grbl_settings unit test_grbl_settings.cpp)
target_link_libraries(test_grbl_settings PRIVATE mc_grbl)

mc_gtest(test_grbl_stream unit test_grbl_stream.cpp)
target_link_libraries(test_grbl_stream PRIVATE mc_grbl)

mc_gtest(test_grbl_server unit test_grbl_server.cpp)
target_link_libraries(test_grbl_server PRIVATE mc_grbl)

# The engine on the board backend and the virtual board in process, in board
# time: streaming with look-ahead, hold, overrides, dwells, faults, resets.
# The 10,000-line stress test streams 50 s of board time: 55 s here, more under ASan.
mc_gtest(test_grbl_board system TIMEOUT 900 test_grbl_board.cpp)
target_link_libraries(test_grbl_board PRIVATE mc_grbl mc_vboard)

# motionctl serve itself: errors, a live run over TCP, SIGTERM, the settings file.
mc_gtest(test_grbl_cli unit test_grbl_cli.cpp)
target_compile_definitions(test_grbl_cli PRIVATE MOTIONCTL_PATH="$<TARGET_FILE:motionctl>")
add_dependencies(test_grbl_cli motionctl)

# Real senders (label client), each running a job on `motionctl serve
# --dry-run` (and below on --sim) with a hold, a resume and a feed override: cncjs 1.11.5 (from npm
# by scripts/deps.sh) through its own server and socket.io API, and Debian's
# bCNC through its Sender class, on the PTY and on socket://.
find_program(MC_NODE node)
set(MC_CNCJS_DIR "$ENV{HOME}/.cache/motioncore/cncjs-1.11.5" CACHE PATH "cncjs as scripts/deps.sh installs it")
if(DEFINED ENV{MC_CNCJS_DIR})
  set(MC_CNCJS_DIR "$ENV{MC_CNCJS_DIR}")
endif()
add_test(NAME GrblClient.cncjs
  COMMAND ${MC_NODE} ${CMAKE_CURRENT_SOURCE_DIR}/test_grbl_cncjs.js $<TARGET_FILE:motionctl> ${MC_CNCJS_DIR})
set_tests_properties(GrblClient.cncjs PROPERTIES LABELS client TIMEOUT 300)
# Debian's python3 by path: bCNC needs Debian's tk and pyserial, not another python on PATH.
add_test(NAME GrblClient.bcnc COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test_grbl_bcnc.py $<TARGET_FILE:motionctl>)
set_tests_properties(GrblClient.bcnc PROPERTIES LABELS client TIMEOUT 300 COST 300)
# The same senders on `motionctl --sim serve`: the board backend, the planner
# and the virtual board, with a shorter job (the virtual board runs in real time).
add_test(NAME GrblClient.cncjs.sim
  COMMAND ${MC_NODE} ${CMAKE_CURRENT_SOURCE_DIR}/test_grbl_cncjs.js $<TARGET_FILE:motionctl> ${MC_CNCJS_DIR} --sim)
set_tests_properties(GrblClient.cncjs.sim PROPERTIES LABELS client TIMEOUT 180)
add_test(NAME GrblClient.bcnc.sim
  COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test_grbl_bcnc.py $<TARGET_FILE:motionctl> --sim)
set_tests_properties(GrblClient.bcnc.sim PROPERTIES LABELS client TIMEOUT 180)
target_compile_definitions(test_grbl_board PRIVATE MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
# A job's start from cncjs on the virtual board: home ($H), touch off (G38.2,
# G10 L20) and an engraving levelled by the map `motionctl level probe` took
# (serve --level). Label `paced` too: its minute and a half of paced board
# time stretches to four under the sanitizers, which make test-sanitize skips
# (GrblBoard.* runs the same backend paths under them in board time).
add_test(NAME GrblClient.cncjs.cycles
  COMMAND ${MC_NODE} ${CMAKE_CURRENT_SOURCE_DIR}/test_grbl_cncjs.js $<TARGET_FILE:motionctl> ${MC_CNCJS_DIR} --cycles)
set_tests_properties(GrblClient.cncjs.cycles PROPERTIES LABELS "client;paced" TIMEOUT 450 COST 450)

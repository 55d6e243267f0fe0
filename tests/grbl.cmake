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

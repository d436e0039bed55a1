# Scheduling hints for `ctest -j`: the GoogleTest cases measured longest (seconds on the 2-core
# CI machine, fresh clone) start first, so that the suite's wall time
# approaches the sum of the test times over the cores instead of ending with one long test
# alone. CTest uses COST only to order tests; it changes nothing a test asserts. Read by ctest
# after the discovered tests (TEST_INCLUDE_FILES, appended last in tests/CMakeLists.txt); the
# netns tests (add_test) get theirs in tests/CMakeLists.txt.
set_tests_properties(Identify.CleanRunsFindNothing PROPERTIES COST 139)
set_tests_properties(PlanCli.SmallObstaclePlansWithTheDefaultBoxAndPassesCheck PROPERTIES COST 37)
set_tests_properties(Identify.CommandDelayAndLagAreTheDocumentedPair PROPERTIES COST 26)

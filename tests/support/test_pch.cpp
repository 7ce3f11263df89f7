// the object the suites' precompiled header is made for (tests/CMakeLists.txt): nothing else

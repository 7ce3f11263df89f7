# bench_ik: pba IK solvers against orocos KDL (Debian liborocos-kdl-dev).
find_package(orocos_kdl REQUIRED)
target_include_directories(bench_ik PRIVATE ${orocos_kdl_INCLUDE_DIRS} ${PROJECT_SOURCE_DIR}/tests/support)
# the heap-allocation counter shared with the zero-allocation tests
target_sources(bench_ik PRIVATE ${PROJECT_SOURCE_DIR}/tests/support/alloc_count.cpp)
target_link_libraries(bench_ik PRIVATE ${orocos_kdl_LIBRARIES} Eigen3::Eigen)

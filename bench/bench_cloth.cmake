# bench_cloth: pba cloth (XPBD) against Bullet soft bodies (Debian libbullet-dev).
# Debian's BulletConfig.cmake holds relative paths, so Bullet is found through its
# pkg-config file: `bullet` is the default single-precision build (btScalar = float),
# the one Bullet's own demos and most users run.
find_package(PkgConfig REQUIRED)
pkg_check_modules(PBA_BULLET REQUIRED IMPORTED_TARGET bullet)
target_include_directories(bench_cloth PRIVATE ${PROJECT_SOURCE_DIR}/tests/support)
# the heap-allocation counter shared with the zero-allocation tests
target_sources(bench_cloth PRIVATE ${PROJECT_SOURCE_DIR}/tests/support/alloc_count.cpp)
target_link_libraries(bench_cloth PRIVATE PkgConfig::PBA_BULLET)

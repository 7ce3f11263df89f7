# bench_rigid: pba rigid bodies against Bullet 3.24 (Debian libbullet-dev, float build, one
# core: Debian's Bullet has no task scheduler) on the same scenes, in one process.
find_package(PkgConfig REQUIRED)
pkg_check_modules(PBA_BULLET_RIGID REQUIRED IMPORTED_TARGET bullet)
target_link_libraries(bench_rigid PRIVATE PkgConfig::PBA_BULLET_RIGID)

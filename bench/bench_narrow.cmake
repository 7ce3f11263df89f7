# bench_narrow: pba's narrow phase against Bullet's box-box detector and its GJK + hull
# clipping path (Debian libbullet-dev, found through pkg-config as in bench_cloth.cmake).
find_package(PkgConfig REQUIRED)
pkg_check_modules(PBA_BULLET REQUIRED IMPORTED_TARGET bullet)
target_link_libraries(bench_narrow PRIVATE PkgConfig::PBA_BULLET)

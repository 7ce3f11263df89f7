# bench_collide: pba's broad phase against Bullet's collision world and ODE's spaces, both
# from Debian (libbullet-dev, libode-dev), through their pkg-config files (Debian's
# BulletConfig.cmake holds relative paths; `bullet` is the default single-precision build).
find_package(PkgConfig REQUIRED)
pkg_check_modules(PBA_BULLET REQUIRED IMPORTED_TARGET bullet)
pkg_check_modules(PBA_ODE REQUIRED IMPORTED_TARGET ode)
target_link_libraries(bench_collide PRIVATE PkgConfig::PBA_BULLET PkgConfig::PBA_ODE)

# bench_rigid: pba rigid bodies against Bullet 3.24 (Debian libbullet-dev, float build, one
# core: Debian's Bullet has no task scheduler) and ODE 0.16 (libode-dev, double) on the same
# scenes, in one process. Both through their pkg-config files (Debian's BulletConfig.cmake
# holds relative paths). The scene table and the two peers are in bench/rigid/.
find_package(PkgConfig REQUIRED)
pkg_check_modules(PBA_BULLET_RIGID REQUIRED IMPORTED_TARGET bullet)
pkg_check_modules(PBA_ODE_RIGID REQUIRED IMPORTED_TARGET ode)
target_sources(bench_rigid PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/rigid/bench_scenes.cpp
                                   ${CMAKE_CURRENT_SOURCE_DIR}/rigid/peer_bullet.cpp
                                   ${CMAKE_CURRENT_SOURCE_DIR}/rigid/peer_ode.cpp)
target_include_directories(bench_rigid PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
target_link_libraries(bench_rigid PRIVATE PkgConfig::PBA_BULLET_RIGID PkgConfig::PBA_ODE_RIGID)

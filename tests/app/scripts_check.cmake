cmake_policy(SET CMP0057 NEW)  # if(IN_LIST) in script mode
# scripts/run needs no benchmark packages; scripts/install-deps installs them only with
# --bench, which scripts/test passes (it builds the benchmarks).
#   cmake -DSOURCE=<checkout> -DWORKDIR=<dir> -P scripts_check.cmake
# scripts/run is run for real against stand-ins for dpkg (every package "missing"),
# apt-get, sudo and cmake that only log their arguments, so nothing is installed or built;
# its final exec of pba_samples gets --version.
set(bench_packages libbenchmark-dev libbullet-dev liborocos-kdl-dev libode-dev libmujoco-dev)
file(REMOVE_RECURSE ${WORKDIR})
file(MAKE_DIRECTORY ${WORKDIR}/bin)
set(log ${WORKDIR}/calls.log)
foreach(tool dpkg apt-get cmake)
  if(tool STREQUAL dpkg)
    set(body "exit 1")  # "not installed"
  else()
    set(body "exit 0")
  endif()
  file(WRITE ${WORKDIR}/bin/${tool} "#!/bin/sh\necho \"${tool} $*\" >> '${log}'\n${body}\n")
endforeach()
file(WRITE ${WORKDIR}/bin/sudo "#!/bin/sh\nexec \"$@\"\n")
file(CHMOD ${WORKDIR}/bin/dpkg ${WORKDIR}/bin/apt-get ${WORKDIR}/bin/cmake ${WORKDIR}/bin/sudo
     PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)

# install-deps --list: the benchmark packages only with --bench
execute_process(COMMAND bash ${SOURCE}/scripts/install-deps --list OUTPUT_VARIABLE plain RESULT_VARIABLE rc1)
execute_process(COMMAND bash ${SOURCE}/scripts/install-deps --bench --list OUTPUT_VARIABLE full RESULT_VARIABLE rc2)
if(NOT rc1 EQUAL 0 OR NOT rc2 EQUAL 0)
  message(FATAL_ERROR "install-deps --list failed: ${rc1} ${rc2}")
endif()
string(REPLACE "\n" ";" plain "${plain}")
string(REPLACE "\n" ";" full "${full}")
foreach(p ${bench_packages})
  if(p IN_LIST plain)
    message(FATAL_ERROR "install-deps installs ${p} without --bench")
  endif()
  if(NOT p IN_LIST full)
    message(FATAL_ERROR "install-deps --bench does not install ${p}")
  endif()
endforeach()
foreach(p libcli11-dev xvfb libglfw3-dev)
  if(NOT p IN_LIST plain)
    message(FATAL_ERROR "install-deps does not install ${p}")
  endif()
endforeach()

# scripts/run with the stand-ins first on PATH
execute_process(COMMAND ${CMAKE_COMMAND} -E env "PATH=${WORKDIR}/bin:$ENV{PATH}" bash ${SOURCE}/scripts/run --version
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
file(READ ${log} calls)
message("scripts/run exit ${rc}\n${out}${err}--- calls ---\n${calls}")
if(NOT calls MATCHES "apt-get install")
  message(FATAL_ERROR "scripts/run did not install its packages through install-deps")
endif()
foreach(p ${bench_packages})
  if(calls MATCHES "(dpkg -s|apt-get install[^\n]*) ${p}( |\n)")
    message(FATAL_ERROR "scripts/run asks for the benchmark package ${p}")
  endif()
endforeach()
if(NOT calls MATCHES "cmake --preset release[^\n]*-DPBA_BUILD_BENCH=OFF")
  message(FATAL_ERROR "scripts/run configures with the benchmarks on (they need the peers)")
endif()
if(NOT calls MATCHES "cmake --build --preset release --target pba_samples")
  message(FATAL_ERROR "scripts/run does not build pba_samples")
endif()

# scripts/test installs them: it builds the benchmarks (checked by reading it: running it
# here would run the whole suite)
file(READ ${SOURCE}/scripts/test test_script)
if(NOT test_script MATCHES "scripts/install-deps --bench" OR NOT test_script MATCHES "-DPBA_BUILD_BENCH=ON")
  message(FATAL_ERROR "scripts/test must install the benchmark packages and build the benchmarks")
endif()
message("PASS: scripts/run needs no benchmark packages; scripts/test installs them")

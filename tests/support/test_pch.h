// The suites' precompiled header (tests/CMakeLists.txt, PBA_TEST_PCH): GoogleTest, the standard
// headers the suites and the library's headers include, and GLM, parsed once per build instead
// of once per test file (2-3.5 s of each file's compile went to parsing headers, 2026-12-06).
// No pba header: it would put all of pba's names into every file, and a suite's
// `using namespace pba; using namespace pba::ik;` then finds two Methods (pba::Method of
// integrate.h, pba::ik::Method). Every test file still includes what it uses: this header only
// makes those includes cheap, and a build without it (PBA_TEST_PCH=OFF, or under ccache)
// compiles the same files.
#pragma once

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

// what pba/core.h includes of GLM (its names stay in glm::)
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

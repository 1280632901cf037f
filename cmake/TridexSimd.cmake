# TRIDEX_SIMD: the vector instructions the project's own targets are compiled for.
#   auto      the best level the building machine runs (x86-64-v4 with AVX-512, x86-64-v3 with
#             AVX2 and FMA), else the compiler's default; the kernel's inner loops widen with it
#             (include/tridex/mill.hpp: 8, 4 or 2 doubles at a time);
#   native    -march=native;
#   x86-64-v4, x86-64-v3: that level, whatever the building machine;
#   baseline  the compiler's default (SSE2 on x86-64): binaries that run on any x86-64.
# Only the project's targets get the flag: tridex::tridex passes none to its consumers, who
# choose their own (-march=x86-64-v3 or better for the wide paths).
set(TRIDEX_SIMD "auto" CACHE STRING "Vector instructions: auto, native, x86-64-v4, x86-64-v3 or baseline")
set_property(CACHE TRIDEX_SIMD PROPERTY STRINGS auto native x86-64-v4 x86-64-v3 baseline)

include(CheckCXXCompilerFlag)

function(tridex_detect_simd out)
  set(${out} "baseline" PARENT_SCOPE)
  if(CMAKE_CROSSCOMPILING OR NOT CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|AMD64|amd64")
    return()
  endif()
  set(probe ${CMAKE_CURRENT_BINARY_DIR}/tridex_simd_probe.cpp)
  file(WRITE ${probe} [=[
#include <cstdio>
int main() {
  __builtin_cpu_init();
  bool v3 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2");
  bool v4 = v3 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
            __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512cd");
  std::puts(v4 ? "x86-64-v4" : v3 ? "x86-64-v3" : "baseline");
}
]=])
  try_run(run_result compile_result ${CMAKE_CURRENT_BINARY_DIR}/tridex_simd_probe ${probe}
          RUN_OUTPUT_VARIABLE level)
  if(compile_result AND run_result EQUAL 0)
    string(STRIP "${level}" level)
    set(${out} "${level}" PARENT_SCOPE)
  endif()
endfunction()

set(tridex_simd_level "${TRIDEX_SIMD}")
if(TRIDEX_SIMD STREQUAL "auto")
  tridex_detect_simd(tridex_simd_level)
endif()
if(tridex_simd_level MATCHES "^x86-64-v[34]$|^native$")
  check_cxx_compiler_flag(-march=${tridex_simd_level} tridex_has_march_${tridex_simd_level})
  if(tridex_has_march_${tridex_simd_level})
    add_compile_options(-march=${tridex_simd_level})
  else()
    message(WARNING "TRIDEX_SIMD: the compiler does not accept -march=${tridex_simd_level}; building for its default")
    set(tridex_simd_level "baseline")
  endif()
elseif(NOT tridex_simd_level STREQUAL "baseline")
  message(FATAL_ERROR "TRIDEX_SIMD must be auto, native, x86-64-v4, x86-64-v3 or baseline, not '${TRIDEX_SIMD}'")
endif()
message(STATUS "tridex: vector instructions ${tridex_simd_level} (TRIDEX_SIMD=${TRIDEX_SIMD})")

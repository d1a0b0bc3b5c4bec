# ctest script: a wide-SIMD build of the step passes (physics/step_<ISA>.cpp) must export nothing
# but its table function. Any other defined external symbol (an out-of-line inline function of
# Eigen, quat.hpp or the standard library) would be an AVX2 copy that the linker may pick for the
# SSE2 code too, and that copy would crash on a CPU without AVX2.
# Usage: cmake -DNM=<nm> -DISA=<avx2|avx512> -DOBJECTS=<list of physics objects>
#        -P check_isa_symbols.cmake
set(object "")
foreach(o IN LISTS OBJECTS)
  if(o MATCHES "step_${ISA}\\.cpp\\.o$")
    set(object "${o}")
  endif()
endforeach()
if(object STREQUAL "")
  message(FATAL_ERROR "step_${ISA}.cpp.o not among the physics objects: ${OBJECTS}")
endif()
execute_process(COMMAND "${NM}" --defined-only --extern-only -C "${object}"
                OUTPUT_VARIABLE symbols RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "nm failed on ${object}")
endif()
string(STRIP "${symbols}" symbols)
string(REPLACE "\n" ";" lines "${symbols}")
# DW.ref.__gxx_personality_v0: the exception-handling personality pointer every C++ object with
# unwind tables may carry (data, no code); not a function copy.
list(FILTER lines EXCLUDE REGEX "DW\\.ref\\.__gxx_personality_v0$")
list(JOIN lines "\n" symbols)
list(LENGTH lines count)
message(STATUS "external symbols of ${object}:\n${symbols}")
if(NOT count EQUAL 1 OR NOT symbols MATCHES "softevo::physics::step_kernels_${ISA}\\(\\)")
  message(FATAL_ERROR "step_${ISA}.cpp.o must define exactly one external symbol, "
                      "softevo::physics::step_kernels_${ISA}(); it defines ${count}")
endif()

# mbi_set_warnings(<target>): the project's warning flags on one target.
function(mbi_set_warnings target)
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow=local
      -Wnon-virtual-dtor -Wno-deprecated-copy)
    if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_GREATER_EQUAL 12
       AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
      # GCC 12 at -O3 reports false positives inside libstdc++ string concatenation
      # (-Wrestrict, GCC bug 105651) and Eigen fixed-size blocks (-Warray-bounds, bug 106247).
      target_compile_options(${target} PRIVATE -Wno-restrict -Wno-array-bounds)
    endif()
    if(MBI_WARNINGS_AS_ERRORS)
      target_compile_options(${target} PRIVATE -Werror)
    endif()
  endif()
endfunction()

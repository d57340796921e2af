# mbi_add_library(<name> [HEADER_ONLY] [INSTALL] [PUBLIC <deps>...] [PRIVATE <deps>...]
#                 [ONLY <files>...] [EXCLUDE <files>...])
#
# The one way an mbi library target is defined: target mbi_<name>, alias mbi::<name>, sources
# src/**/*.cpp of the calling folder (ONLY: just these; EXCLUDE: all but these; paths relative to
# the folder: a build configured without a dependency leaves out the files that need it), public
# headers include/ (installed as include/mbi/...), C++20, the project's warnings. INSTALL exports
# it in mbiTargets (find_package(mbi)); only libraries whose dependencies a consumer can find
# (Eigen, Threads) are installed.
function(mbi_add_library name)
  cmake_parse_arguments(L "HEADER_ONLY;INSTALL" "" "PUBLIC;PRIVATE;ONLY;EXCLUDE" ${ARGN})
  set(target mbi_${name})
  if(L_HEADER_ONLY)
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE
      $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
      $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
    target_compile_features(${target} INTERFACE cxx_std_20)
    target_link_libraries(${target} INTERFACE ${L_PUBLIC})
  else()
    file(GLOB_RECURSE sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp)
    if(L_ONLY)
      set(sources)
      foreach(f IN LISTS L_ONLY)
        list(APPEND sources ${CMAKE_CURRENT_SOURCE_DIR}/${f})
      endforeach()
    endif()
    foreach(f IN LISTS L_EXCLUDE)
      list(REMOVE_ITEM sources ${CMAKE_CURRENT_SOURCE_DIR}/${f})
    endforeach()
    if(NOT sources)
      message(FATAL_ERROR "mbi_add_library(${name}): no sources in ${CMAKE_CURRENT_SOURCE_DIR}/src")
    endif()
    add_library(${target} ${sources})
    target_include_directories(${target} PUBLIC
      $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
      $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
    target_compile_features(${target} PUBLIC cxx_std_20)
    target_link_libraries(${target} PUBLIC ${L_PUBLIC} PRIVATE ${L_PRIVATE})
    mbi_set_warnings(${target})
  endif()
  add_library(mbi::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME ${target})
  if(L_INSTALL)
    install(TARGETS ${target} EXPORT mbiTargets
      ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
    install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  endif()
endfunction()

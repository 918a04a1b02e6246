# The packaging test (ctest package_installs_and_a_client_builds): installs limber from BUILD_DIR
# into WORK_DIR/prefix, builds a client with find_package(limber) whose main.cpp is the first
# ```cpp block of README.md, runs it, and checks that a translation unit compiled for another
# instruction set than the library is refused at build time: the example, and every installed
# header included alone (a client that includes only, say, the Featherstone headers must be
# refused too, not crash freeing an Eigen object with the wrong alignment).
#
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DNATIVE=ON|OFF -DCXX=... -DEIGEN_DIR=... -P package_test.cmake
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE output ERROR_VARIABLE output)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "failed (${result}): ${ARGN}\n${output}")
  endif()
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)

# The README's example, as written.
file(READ ${SOURCE_DIR}/README.md readme)
string(FIND "${readme}" "```cpp\n" begin)
if(begin EQUAL -1)
  message(FATAL_ERROR "README.md has no ```cpp block")
endif()
math(EXPR begin "${begin} + 7")
string(SUBSTRING "${readme}" ${begin} -1 rest)
string(FIND "${rest}" "```" end)
string(SUBSTRING "${rest}" 0 ${end} example)
file(COPY ${SOURCE_DIR}/tests/package/client/CMakeLists.txt DESTINATION ${WORK_DIR}/client)
file(WRITE ${WORK_DIR}/client/main.cpp "${example}")
# A second translation unit through the umbrella header alone: it must compile and link with the first.
file(WRITE ${WORK_DIR}/client/umbrella.cpp
     "#include <limber/limber.hpp>\nlimber::WorldOptions umbrella_options() { return limber::WorldOptions{}; }\n")

# The generator CMake picks by itself (Unix Makefiles), as the README's command does.
run(${CMAKE_COMMAND} -S ${WORK_DIR}/client -B ${WORK_DIR}/client-build -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_CXX_COMPILER=${CXX})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/client-build)
run(${WORK_DIR}/client-build/client)

# A translation unit built for another instruction set must not compile against the headers.
if(NATIVE)
  set(other_flags "")
else()
  set(other_flags "-march=native")
endif()
execute_process(COMMAND ${CXX} -std=c++20 ${other_flags} -fsyntax-only -I${WORK_DIR}/prefix/include -I${EIGEN_DIR}
                        ${WORK_DIR}/client/main.cpp
                RESULT_VARIABLE result OUTPUT_VARIABLE output ERROR_VARIABLE output)
if(result EQUAL 0)
  if(NATIVE)
    message(FATAL_ERROR "a translation unit without -march=native compiled against a native limber")
  else()
    message(STATUS "this CPU's -march=native defines nothing the portable build lacks: nothing to mismatch")
  endif()
elseif(NOT output MATCHES "instruction-set mismatch")
  message(FATAL_ERROR "the mismatched build failed, but not with limber's message:\n${output}")
else()
  # Each installed header alone, preprocessed only (the #error is the preprocessor's): every one
  # must reach limber/config.hpp.
  file(GLOB_RECURSE headers RELATIVE ${WORK_DIR}/prefix/include ${WORK_DIR}/prefix/include/limber/*.hpp)
  list(REMOVE_ITEM headers limber/config.hpp)
  set(unguarded "")
  foreach(header IN LISTS headers)
    file(WRITE ${WORK_DIR}/one_header.cpp "#include <${header}>\n")
    execute_process(COMMAND ${CXX} -std=c++20 ${other_flags} -Wfatal-errors -E -o /dev/null -I${WORK_DIR}/prefix/include -I${EIGEN_DIR}
                            ${WORK_DIR}/one_header.cpp
                    RESULT_VARIABLE result OUTPUT_VARIABLE output ERROR_VARIABLE output)
    if(result EQUAL 0 OR NOT output MATCHES "instruction-set mismatch")
      list(APPEND unguarded ${header})
    endif()
  endforeach()
  list(LENGTH headers count)
  if(count LESS 20)
    message(FATAL_ERROR "only ${count} headers installed under ${WORK_DIR}/prefix/include/limber")
  endif()
  if(unguarded)
    list(JOIN unguarded "\n  " unguarded)
    message(FATAL_ERROR "installed headers that a translation unit for another instruction set can include without "
                        "limber's #error (include limber/config.hpp in each):\n  ${unguarded}")
  endif()
endif()

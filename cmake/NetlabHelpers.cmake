# Helpers shared by every target of netlab: one way to add a library, one way to add a test.

# Compile options every netlab target gets: warnings, and sanitizers when asked for.
function(netlab_target_defaults target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                           -Wno-deprecated-copy)
  if(NETLAB_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(NETLAB_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
                                             -fno-sanitize-recover=undefined)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
    # Eigen turns its "glibc malloc is 16-byte aligned" assumption off under __SANITIZE_ADDRESS__
    # and then frees through its hand-made aligned allocator, which reads an offset stored before
    # the block. Debian's libceres is built without the sanitizer, so a matrix it allocates with
    # plain malloc and our code frees (ceres::GradientChecker's jacobians) was reported as a
    # heap-buffer-overflow. Keep the library's choice: ASan's malloc is 16-byte aligned on x86-64.
    target_compile_definitions(${target} PRIVATE EIGEN_MALLOC_ALREADY_ALIGNED=1)
  endif()
endfunction()

# netlab_add_library(NAME SOURCES a.cc b.cc DEPS lib1 lib2 [PRIVATE_DEPS ...])
# Includes are spelled from the repository root ("libnetsim/model.h"); the target carries that path.
function(netlab_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  # sqrt without the errno branch (netlab never reads errno): fewer instructions in hot loops.
  target_compile_options(${name} PRIVATE -fno-math-errno)
  netlab_target_defaults(${name})
endfunction()

# netlab_add_test(NAME SOURCES a_test.cc DEPS lib [LABELS slow] [OWN_MAIN])
# One gtest binary per source file, registered with ctest by gtest_discover_tests. OWN_MAIN: the
# test defines main() itself (Qt tests make their QApplication there).
function(netlab_add_test name)
  cmake_parse_arguments(ARG "OWN_MAIN" "TIMEOUT" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest)
  if(NOT ARG_OWN_MAIN)
    target_link_libraries(${name} PRIVATE GTest::gtest_main)
  endif()
  target_compile_definitions(${name} PRIVATE
    NETLAB_SOURCE_DIR="${PROJECT_SOURCE_DIR}" NETLAB_BINARY_DIR="${PROJECT_BINARY_DIR}")
  netlab_target_defaults(${name})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
                       PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}")
endfunction()

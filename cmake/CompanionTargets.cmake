# Compile options for companion's own targets (not for third-party headers).
add_library(companion_options INTERFACE)
target_compile_options(companion_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
  -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual
  -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough)
if(COMPANION_WERROR)
  target_compile_options(companion_options INTERFACE -Werror)
endif()
if(COMPANION_SANITIZE)
  target_compile_options(companion_options INTERFACE
    -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  target_link_options(companion_options INTERFACE -fsanitize=address,undefined)
endif()
if(COMPANION_FUZZ)
  # Everything instrumented for coverage, plus address/undefined checks.
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()
if(COMPANION_TSAN)
  target_compile_options(companion_options INTERFACE -fsanitize=thread -fno-omit-frame-pointer)
  target_link_options(companion_options INTERFACE -fsanitize=thread)
endif()

# companion_library(NAME SOURCES... [DEPS ...]) : one layer library with include/ as public root.
function(companion_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} PRIVATE companion_options ${ARG_PRIVATE_DEPS})
endfunction()

# Included by bench/gpu/CMakeLists.txt with -DMANIBENCH_PREBUILT=DIR: the
# targets learning/CMakeLists.txt links (manibench::sdk, manibench::core,
# manibench_cli, nlohmann_json, manibench_add_tree_plugin), made from the
# bundle of bench/gpu_bundle.sh instead of the tree's own build, then
# learning/CMakeLists.txt itself. torch and yaml-cpp are the including
# file's.

# The bundle's link line: bin/manibench's as built on the Debian machine
# (static/NAME.a, sys/lib/SONAME, -lNAME), in its order.
include(${MANIBENCH_PREBUILT}/link.cmake)
message(STATUS "manibench prebuilt: ${MANIBENCH_PREBUILT} (commit ${MANIBENCH_PREBUILT_COMMIT}, ${MANIBENCH_PREBUILT_BUILT_WITH})")
set(prebuilt_core_link)
foreach(item IN LISTS MANIBENCH_PREBUILT_CORE_LINK)
  if(item MATCHES "^-l")
    list(APPEND prebuilt_core_link ${item})
    continue()
  endif()
  get_filename_component(name ${item} NAME)
  string(MAKE_C_IDENTIFIER "prebuilt_${name}" target)
  if(name STREQUAL "libmanibench_cli.a")
    set(target manibench_cli)  # the name learning/CMakeLists.txt links
  endif()
  if(NOT TARGET ${target})
    if(item MATCHES "\\.a$")
      add_library(${target} STATIC IMPORTED)
    else()
      add_library(${target} SHARED IMPORTED)
      set_target_properties(${target} PROPERTIES IMPORTED_SONAME ${name})
    endif()
    set_target_properties(${target} PROPERTIES IMPORTED_LOCATION ${MANIBENCH_PREBUILT}/${item})
  endif()
  if(target STREQUAL "manibench_cli")
    set(prebuilt_cli ${target})
  else()
    list(APPEND prebuilt_core_link ${target})
  endif()
endforeach()
if(NOT prebuilt_cli)
  message(FATAL_ERROR "${MANIBENCH_PREBUILT}/link.cmake names no static/libmanibench_cli.a")
endif()

# manibench::sdk (sdk/CMakeLists.txt): the SDK's headers over Eigen, yaml-cpp
# and Boost's headers, here the bundle's.
add_library(manibench_sdk INTERFACE)
add_library(manibench::sdk ALIAS manibench_sdk)
target_include_directories(manibench_sdk INTERFACE ${ROOT}/sdk/include)
target_include_directories(manibench_sdk SYSTEM INTERFACE ${MANIBENCH_PREBUILT}/sys/include/eigen3
                                                          ${MANIBENCH_PREBUILT}/sys/include)
target_compile_definitions(manibench_sdk INTERFACE BOOST_ALL_NO_LIB)
target_link_libraries(manibench_sdk INTERFACE yaml-cpp)
target_compile_features(manibench_sdk INTERFACE cxx_std_17)

# manibench::core (core/CMakeLists.txt): every layer's public headers, and
# the static layers with their shared libraries. The linker finds what
# those libraries load in the bundle (-rpath-link), not in the environment:
# the toolchain runs without the bundle's LD_LIBRARY_PATH.
add_library(manibench_core INTERFACE)
add_library(manibench::core ALIAS manibench_core)
foreach(layer workers scene render observation runtime config trajectory evaluation demos)
  target_include_directories(manibench_core INTERFACE ${ROOT}/core/${layer}/include)
endforeach()
target_link_libraries(manibench_core INTERFACE manibench::sdk ${prebuilt_core_link})
target_link_options(manibench_core INTERFACE "LINKER:-rpath-link,${MANIBENCH_PREBUILT}/sys/lib")

# manibench_cli (apps/CMakeLists.txt): the CLI's helpers manibench-train shares.
set_target_properties(${prebuilt_cli} PROPERTIES
  INTERFACE_INCLUDE_DIRECTORIES ${ROOT}/apps/manibench
  INTERFACE_LINK_LIBRARIES manibench::core)
add_library(nlohmann_json::nlohmann_json ALIAS manibench_sdk)  # header-only: the bundle's headers

# The plugin function the tree's plugins use (sdk/cmake/ManibenchPlugin.cmake),
# with the host's plugin folder in the bundle as the tree's plugin folder.
set(CMAKE_INSTALL_LIBDIR lib)
set(CMAKE_INSTALL_BINDIR bin)
set(MANIBENCH_PLUGIN_SUBDIR lib/manibench/plugins)
include(${ROOT}/sdk/cmake/ManibenchPlugin.cmake)
function(manibench_add_tree_plugin target)
  manibench_add_plugin(${target} ${ARGN} OUTPUT_DIRECTORY "${MANIBENCH_PREBUILT}/${MANIBENCH_PLUGIN_SUBDIR}")
endfunction()

set(BUILD_TESTING OFF)  # learning/tests needs the tree's test support; the model tests are below
add_subdirectory(${ROOT}/learning learning)

# Into the bundle's prefix: manibench-train beside manibench, the runtime
# in lib/manibench (beside the plugin folder: where torch_policy looks).
set_target_properties(manibench-train PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${MANIBENCH_PREBUILT}/bin)
set_target_properties(manibench_learning_runtime PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${MANIBENCH_PREBUILT}/lib/manibench)

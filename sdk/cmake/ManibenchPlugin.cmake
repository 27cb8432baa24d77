# manibench_add_plugin(<target> SOURCES <src>... [LINK_LIBRARIES <lib>...]
#                      [OUTPUT_DIRECTORY <dir>] [INSTALL])
# Builds a plugin library (a MODULE: loaded with dlopen, never linked).
# Symbols are hidden by default so that each plugin keeps its own copy of the
# SDK's registration tables; only the entry point is exported.
function(manibench_add_plugin target)
  cmake_parse_arguments(ARG "INSTALL" "OUTPUT_DIRECTORY" "SOURCES;LINK_LIBRARIES" ${ARGN})
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "manibench_add_plugin(${target}): SOURCES is required")
  endif()
  add_library(${target} MODULE ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE manibench::sdk ${ARG_LINK_LIBRARIES})
  set_target_properties(${target} PROPERTIES
    CXX_VISIBILITY_PRESET hidden
    C_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON)
  # A plugin that leaves symbols undefined fails at build time, not at load.
  target_link_options(${target} PRIVATE "LINKER:--no-undefined")
  if(ARG_OUTPUT_DIRECTORY)
    set_target_properties(${target} PROPERTIES LIBRARY_OUTPUT_DIRECTORY "${ARG_OUTPUT_DIRECTORY}")
  endif()
  if(ARG_INSTALL)
    install(TARGETS ${target} LIBRARY DESTINATION "${MANIBENCH_PLUGIN_SUBDIR}")
  endif()
endfunction()

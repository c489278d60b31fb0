# The layer check: data flows one way, so no folder may include a header of a layer above it.
#   cmake -DROOT=<source tree> -P cmake/PectusCheckLayers.cmake
# Exits non-zero and names every offending `file:line: includes "header"` when a lower layer includes a
# higher one. The layers (docs/architecture.md):
#   shape/core <- shape/io <- registration <- shape/{render,surface,model} <- shape/pipeline, datasets
#   <- planner_plugin, apps
# Within shape/{render,surface,model}: model may draw with render; render, surface and model use nothing
# else of each other. The planner plugin proper (everything but planner_plugin/host, the host side that
# reads the shape model) is loaded into other programs and sees only shape/core and shape/io.
# A header in an internal/ sub-folder of a library (registration/internal/icp_steps.h) is included only by
# that library's own files. tests/ may include anything and is not checked.
if(NOT ROOT)
  message(FATAL_ERROR "PectusCheckLayers: pass -DROOT=<source tree>")
endif()

# folder -> the top-level include prefixes its files may use (besides its own folder).
set(allowed_shape/core "")
set(allowed_shape/io "shape/core")
set(allowed_registration "shape/core;shape/io")
set(allowed_shape/render "shape/core;shape/io;registration")
set(allowed_shape/surface "shape/core;shape/io;registration")
set(allowed_shape/model "shape/core;shape/io;registration;shape/render")
set(allowed_shape/pipeline "shape/core;shape/io;registration;shape/render;shape/surface;shape/model")
set(allowed_datasets "shape/core;shape/io;registration;shape/render;shape/surface;shape/model")
set(allowed_planner_plugin "shape/core;shape/io")
set(allowed_planner_plugin/host
    "shape/core;shape/io;registration;shape/render;shape/surface;shape/model;shape/pipeline;planner_plugin")
set(allowed_apps
    "shape/core;shape/io;registration;shape/render;shape/surface;shape/model;shape/pipeline;datasets;planner_plugin")
# The folders checked, most specific first (planner_plugin/host before planner_plugin).
set(layers shape/core shape/io registration shape/render shape/surface shape/model shape/pipeline datasets
    planner_plugin/host planner_plugin apps)
# Every include prefix that names a layer of the project (anything else is a system or library header).
set(project_prefixes shape/core shape/io registration shape/render shape/surface shape/model
    shape/pipeline datasets planner_plugin apps tests)

set(violations 0)
set(checked 0)
foreach(layer ${layers})
  if(NOT IS_DIRECTORY "${ROOT}/${layer}")
    continue()
  endif()
  file(GLOB_RECURSE files RELATIVE "${ROOT}" "${ROOT}/${layer}/*.h" "${ROOT}/${layer}/*.cc"
       "${ROOT}/${layer}/*.hpp" "${ROOT}/${layer}/*.cpp")
  foreach(file ${files})
    # A file belongs to the most specific layer listed first that holds it.
    if(layer STREQUAL "planner_plugin" AND file MATCHES "^planner_plugin/host/")
      continue()
    endif()
    if(file MATCHES "/node_modules/")
      continue()
    endif()
    math(EXPR checked "${checked} + 1")
    set(ok ${allowed_${layer}} ${layer})
    if(layer STREQUAL "planner_plugin/host")
      list(APPEND ok planner_plugin)
    endif()
    file(STRINGS "${ROOT}/${file}" lines)
    set(n 0)
    foreach(line IN LISTS lines)
      math(EXPR n "${n} + 1")
      if(NOT line MATCHES "^[ \t]*#[ \t]*include[ \t]*\"([^\"]+)\"")
        continue()
      endif()
      set(header "${CMAKE_MATCH_1}")
      set(target_layer "")
      foreach(prefix ${project_prefixes})
        string(LENGTH "${prefix}/" len)
        string(SUBSTRING "${header}" 0 ${len} head)
        if(head STREQUAL "${prefix}/")
          set(target_layer ${prefix})
          break()
        endif()
      endforeach()
      if(target_layer STREQUAL "")
        continue()  # a library's header, or a relative one
      endif()
      list(FIND ok ${target_layer} found)
      if(found EQUAL -1)
        message("${file}:${n}: includes \"${header}\": ${layer} may not use ${target_layer}")
        math(EXPR violations "${violations} + 1")
      endif()
      # A header in an internal/ folder belongs to its library: only files of that library include it.
      if(header MATCHES "^(.+)/internal/")
        set(owner "${CMAKE_MATCH_1}")
        string(LENGTH "${owner}/" len)
        string(SUBSTRING "${file}" 0 ${len} head)
        if(NOT head STREQUAL "${owner}/")
          message("${file}:${n}: includes \"${header}\": an internal header of ${owner}")
          math(EXPR violations "${violations} + 1")
        endif()
      endif()
    endforeach()
  endforeach()
endforeach()

if(checked EQUAL 0)
  message(FATAL_ERROR "PectusCheckLayers: no source file found under ${ROOT}")
endif()
if(violations GREATER 0)
  message(FATAL_ERROR "layer check: ${violations} include(s) against the direction of the layers "
                      "(docs/architecture.md), in ${checked} files")
endif()
message("layer check: ${checked} files, every include goes down the layers")

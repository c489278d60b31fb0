# The layer check's own test: plant a wrong include in a small tree and expect the check to fail, naming
# the file, the line and the layer; a tree whose includes go down the layers passes.
#   cmake -DCHECK=cmake/PectusCheckLayers.cmake -DWORK=<scratch folder> -P planted_include_test.cmake
file(REMOVE_RECURSE "${WORK}")
file(WRITE "${WORK}/good/shape/core/geometry.h" "#pragma once\n#include <vector>\n")
file(WRITE "${WORK}/good/shape/model/compute_chest_roi.h" "#pragma once\n#include \"shape/core/geometry.h\"\n")
file(WRITE "${WORK}/good/planner_plugin/host/average_chest.h" "#include \"shape/model/compute_chest_roi.h\"\n")
file(WRITE "${WORK}/good/registration/icp.cc" "#include \"registration/internal/icp_steps.h\"\n")
execute_process(COMMAND ${CMAKE_COMMAND} -DROOT=${WORK}/good -P ${CHECK}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the layer check refused a tree whose includes go down the layers:\n${out}${err}")
endif()

set(planted_cases
    "shape/core/geometry.h|shape/model/compute_chest_roi.h|shape/core may not use shape/model"
    "registration/icp.cc|shape/surface/merge_sweeps.h|registration may not use shape/surface"
    "shape/surface/reconstruct_surface.cc|shape/model/compute_chest_roi.h|shape/surface may not use shape/model"
    "planner_plugin/fem/assembly.cc|shape/model/compute_chest_roi.h|planner_plugin may not use shape/model"
    "shape/pipeline/cohort_pipeline.cc|apps/command.h|shape/pipeline may not use apps"
    "shape/surface/reconstruct_surface.cc|registration/internal/icp_steps.h|an internal header of registration")
foreach(case ${planted_cases})
  string(REPLACE "|" ";" parts "${case}")
  list(GET parts 0 file)
  list(GET parts 1 header)
  list(GET parts 2 why)
  file(REMOVE_RECURSE "${WORK}/bad")
  file(COPY "${WORK}/good/" DESTINATION "${WORK}/bad")
  file(WRITE "${WORK}/bad/${file}" "#pragma once\n#include <string>\n#include \"${header}\"\n")
  execute_process(COMMAND ${CMAKE_COMMAND} -DROOT=${WORK}/bad -P ${CHECK}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0)
    message(FATAL_ERROR "the layer check missed a planted include of ${header} in ${file}:\n${out}${err}")
  endif()
  string(FIND "${out}${err}" "${file}:3: includes \"${header}\": ${why}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the layer check failed without naming ${file}:3 and why:\n${out}${err}")
  endif()
endforeach()
message("layer check test: clean tree passes, every planted include caught")

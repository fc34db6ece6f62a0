# `rgbl vocab train` on synthetic images: a vocabulary file that is the same bytes when trained again,
# that `rgbl run` loads through LoopClosing.Vocabulary (relative to the settings file), and errors
# that name the folder or file at fault.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
execute_process(COMMAND ${RGBL_SIM} --out ${WORK_DIR}/data --frames 12 --quiet RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbl_sim failed")
endif()
set(images ${WORK_DIR}/data/sequences/00/image_0)
foreach(name a b)
  execute_process(COMMAND ${RGBL} vocab train ${images} --out ${WORK_DIR}/${name}.rgblvoc --branching 4 --levels 3
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}${err}")
  if(NOT rc EQUAL 0 OR NOT out MATCHES "vocabulary: [0-9]+ words \\([0-9]+ nodes, branching 4, 3 levels\\) from [0-9]+ descriptors of 12 images")
    message(FATAL_ERROR "vocab train failed (exit ${rc})")
  endif()
endforeach()
file(SHA256 ${WORK_DIR}/a.rgblvoc a)
file(SHA256 ${WORK_DIR}/b.rgblvoc b)
if(NOT a STREQUAL b)
  message(FATAL_ERROR "two trainings on the same images differ")
endif()

# the vocabulary in a run, found relative to the settings file
file(MAKE_DIRECTORY ${WORK_DIR}/config)
file(RENAME ${WORK_DIR}/a.rgblvoc ${WORK_DIR}/config/mine.rgblvoc)
file(WRITE ${WORK_DIR}/config/bow.yaml "%YAML:1.0\nLoopClosing.Places: \"bow\"\nLoopClosing.Vocabulary: \"mine.rgblvoc\"\n")
execute_process(COMMAND ${RGBL} -q run ${WORK_DIR}/data/sequences/00 --config ${WORK_DIR}/config/bow.yaml
                        --out ${WORK_DIR}/out RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "ok 12")
  message(FATAL_ERROR "run with the trained vocabulary failed (exit ${rc}): ${out}${err}")
endif()

# errors name what is wrong: expect_error(<what> <regex on stderr> <command...>)
function(expect_error what pattern)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(rc EQUAL 0 OR NOT err MATCHES "${pattern}")
    message(FATAL_ERROR "${what}: expected an error matching '${pattern}', got exit ${rc}: ${err}")
  endif()
endfunction()
set(run ${RGBL} run ${WORK_DIR}/data/sequences/00 --out ${WORK_DIR}/out2 --config)
file(MAKE_DIRECTORY ${WORK_DIR}/empty)
expect_error("a folder without images" "empty.*no \\.png/\\.jpg image"
             ${RGBL} vocab train ${WORK_DIR}/empty --out ${WORK_DIR}/c.rgblvoc)
file(WRITE ${WORK_DIR}/config/mine.rgblvoc "RGBLVOC1 but nothing else")
expect_error("a damaged vocabulary" "mine\\.rgblvoc.*not an rgbl vocabulary" ${run} ${WORK_DIR}/config/bow.yaml)
file(WRITE ${WORK_DIR}/config/bad.yaml "%YAML:1.0\nLoopClosing.Places: \"scan_context,,bow\"\n")
expect_error("an empty recogniser name" "bad\\.yaml.*LoopClosing\\.Places" ${run} ${WORK_DIR}/config/bad.yaml)
file(WRITE ${WORK_DIR}/config/unknown.yaml "%YAML:1.0\nLoopClosing.Places: \"scan_context, netvlad\"\n")
expect_error("an unknown recogniser" "loop_closing\\.places.*bow, scan_context.*netvlad"
             ${run} ${WORK_DIR}/config/unknown.yaml)
file(REMOVE_RECURSE ${WORK_DIR})

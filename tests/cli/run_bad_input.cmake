# `rgbl run` on bad input: a missing folder, a truncated .bin in the middle of the sequence, a bad
# --config YAML and a bad --depth spec. Each must exit non-zero with one "error: " line naming the
# file, option or key, without a stack trace, and leave no trajectory file that looks complete (not
# even one from an earlier successful run in the same --out folder).
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
execute_process(COMMAND ${RGBL_SIM} --out ${WORK_DIR}/data --frames 8 --width 306 --height 92 --quiet
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbl_sim failed: ${out}${err}")
endif()
set(seq ${WORK_DIR}/data/sequences/00)
set(out_dir ${WORK_DIR}/out)

# A run that works, so that the failures below start from a folder holding complete outputs.
execute_process(COMMAND ${RGBL} --quiet run ${seq} --out ${out_dir} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${out_dir}/trajectory_kitti.txt)
  message(FATAL_ERROR "the clean run failed (${rc}): ${out}${err}")
endif()

function(expect_failure expected)
  execute_process(COMMAND ${RGBL} --quiet run ${ARGN} --out ${out_dir} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  message("rgbl run ${ARGN}\n  exit ${rc}: ${err}")
  if(rc EQUAL 0)
    message(FATAL_ERROR "rgbl run ${ARGN} succeeded")
  endif()
  if(NOT err MATCHES "^error: [^\n]*\n$")
    message(FATAL_ERROR "stderr is not exactly one 'error: ' line")
  endif()
  if(NOT err MATCHES "${expected}")
    message(FATAL_ERROR "the error lacks '${expected}'")
  endif()
  if(err MATCHES "terminate called|Aborted|what\\(\\)|stoi|basic_string")
    message(FATAL_ERROR "looks like a crash or a raw library message")
  endif()
  foreach(name trajectory_kitti.txt trajectory_tum.txt summary.json)
    if(EXISTS ${out_dir}/${name})
      message(FATAL_ERROR "${out_dir}/${name} exists after a failed run")
    endif()
  endforeach()
  file(GLOB parts ${out_dir}/*.part)
  if(parts)
    message(FATAL_ERROR "left-over partial files: ${parts}")
  endif()
endfunction()

# missing folder
expect_failure("nope: not a folder" ${WORK_DIR}/nope)

# a truncated scan in the middle (20 bytes: not a multiple of 16)
file(COPY ${seq}/ DESTINATION ${WORK_DIR}/truncated)
file(WRITE ${WORK_DIR}/truncated/velodyne/000004.bin "twenty bytes of junk")
expect_failure("000004\\.bin: size 20 bytes is not a multiple of 16" ${WORK_DIR}/truncated)

# bad settings: not YAML, a non-numeric value, an incomplete group, a missing file
file(WRITE ${WORK_DIR}/broken.yaml "%YAML:1.0\nCamera.fx: [1, 2\nCamera.fy: {\n")
expect_failure("broken\\.yaml" ${seq} --config ${WORK_DIR}/broken.yaml)
file(WRITE ${WORK_DIR}/text.yaml "%YAML:1.0\nORBextractor.nFeatures: many\n")
expect_failure("text\\.yaml: key 'ORBextractor\\.nFeatures': expected an integer, found the string 'many'" ${seq}
               --config ${WORK_DIR}/text.yaml)
file(WRITE ${WORK_DIR}/partial.yaml "%YAML:1.0\nCamera.fx: 300.0\nCamera.fy: 300.0\nCamera.cx: 150.0\n")
expect_failure("partial\\.yaml: key 'Camera\\.cy'" ${seq} --config ${WORK_DIR}/partial.yaml)
file(WRITE ${WORK_DIR}/method.yaml "LiDAR.Method: \"Foo\"\n")
expect_failure("method\\.yaml: invalid option 'LiDAR\\.Method': expected InverseDilation" ${seq}
               --config ${WORK_DIR}/method.yaml)
expect_failure("absent\\.yaml: missing" ${seq} --config ${WORK_DIR}/absent.yaml)

# bad depth specs
expect_failure("--depth.*'lidar:diamond'" ${seq} --depth lidar:diamond)
expect_failure("--depth.*'lidar:diamond99999999999'" ${seq} --depth lidar:diamond99999999999)
expect_failure("--depth.*'lidar:diamond5x'" ${seq} --depth lidar:diamond5x)
expect_failure("--depth.*'sonar'" ${seq} --depth sonar)

# A run that tracks no frame (100 features: too few with depth to initialise) fails: one error line
# naming the count, no trajectory files (they would hold only guesses), summary.json and timing.csv
# kept to tell why.
file(WRITE ${WORK_DIR}/few.yaml "%YAML:1.0\nORBextractor.nFeatures: 100\n")
execute_process(COMMAND ${RGBL} --quiet run ${seq} --config ${WORK_DIR}/few.yaml --out ${out_dir}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("rgbl run with 100 features\n  exit ${rc}: ${err}")
if(rc EQUAL 0 OR NOT err MATCHES "^error: no frame of 8 was tracked \\(8 not initialised, 0 lost\\)[^\n]*\n$")
  message(FATAL_ERROR "a run tracking nothing did not fail with one error line")
endif()
foreach(name trajectory_kitti.txt trajectory_tum.txt)
  if(EXISTS ${out_dir}/${name})
    message(FATAL_ERROR "${out_dir}/${name} exists after a run that tracked nothing")
  endif()
endforeach()
file(READ ${out_dir}/summary.json summary)
if(NOT summary MATCHES "\"frames_tracked\": 0," OR NOT summary MATCHES "\"tracked\": null")
  message(FATAL_ERROR "summary.json does not say that no frame was tracked")
endif()

# rgbl_image_stats prints a markdown row of statistics for a scenario (and for the KITTI excerpt when
# the data is there), with plausible values.
execute_process(COMMAND ${STATS} --frames 1 scenario:plain RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbl_image_stats failed with exit code ${rc}")
endif()
if(NOT out MATCHES "\\| source \\| frames \\| size \\| mean \\| std \\|")
  message(FATAL_ERROR "no header")
endif()
# mean grey 40..160, ORB keypoints in the thousands, LiDAR returns in the image in the ten thousands
if(NOT out MATCHES "\\| scenario plain \\| 1 \\| 613x185 \\| ([4-9][0-9]|1[0-5][0-9])\\.[0-9] \\| [0-9.]+ \\| [0-9.]+ \\| [0-9.]+ \\| [0-9.]+ \\| 1[0-9][0-9][0-9] \\| [0-9]+ \\| [0-9.]+ \\| [0-9.]+ \\| 1[0-9][0-9][0-9][0-9] \\|")
  message(FATAL_ERROR "implausible statistics for the plain scenario")
endif()
execute_process(COMMAND ${STATS} scenario:no-such RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "scenario")
  message(FATAL_ERROR "an unknown scenario must fail naming it")
endif()

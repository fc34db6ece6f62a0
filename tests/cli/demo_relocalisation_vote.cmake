# Traffic seed 3 (80 frames) tracked with ORBextractor.nFeatures 1900 and the ring plane fit
# (LiDAR.SurfaceFitWindowDeg 0.5): at frame 54 the scans refuse a 0.74 m step, and the relocalisation
# asked next lands beside it. Taken on 261 against 255 inliers it lost the map at frame 61 (ATE 4.96 m);
# the LiDAR's vote on it keeps the prediction (ATE 0.096 m, every frame tracked; docs/tracking.md).
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
execute_process(COMMAND ${RGBL} -q demo --scenario traffic --frames 80 --seed 3 --keep ${WORK_DIR}/street
                        --out ${WORK_DIR}/demo
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbl demo failed with exit code ${rc}: ${out}${err}")
endif()
file(WRITE ${WORK_DIR}/settings.yaml "%YAML:1.0\nORBextractor.nFeatures: 1900\nLiDAR.SurfaceFitWindowDeg: 0.5\n")
execute_process(COMMAND ${RGBL} run ${WORK_DIR}/street/sequences/00 --config ${WORK_DIR}/settings.yaml
                        --out ${WORK_DIR}/out
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbl run failed with exit code ${rc}")
endif()
if(NOT out MATCHES "ok ([0-9]+), weak ([0-9]+), lost 0, not initialised 0")
  message(FATAL_ERROR "a frame lost or not initialised")
endif()
if(NOT out MATCHES "ATE RMSE ([0-9]+\\.[0-9]+) m")
  message(FATAL_ERROR "no ATE in the summary")
endif()
if(CMAKE_MATCH_1 GREATER 0.2)
  message(FATAL_ERROR "ATE ${CMAKE_MATCH_1} m above 0.2 m")
endif()

# A straight 1000 m drive along z (1 m per frame) and an estimate with a 2 % scale error.
# Hand-computed: a KITTI segment of length L ends L + 1 frames later (first frame BEYOND start + L), so
# t_err(L) = 2 (L + 1) / L %: 2.0200 % for 100 m (90 segments), 2.0100 % for 200 m (80 segments),
# 2.0153 % over all 170; r_err 0. ATE after rigid alignment: 0.02 * |i - 500|, RMSE 0.02 * sqrt(83500)
# = 5.7793 m. RPE 0.02 m per frame. End-point drift 20 m = 2 %. The estimate's path 1020 m.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(gt "")
set(est "")
foreach(i RANGE 0 1000)
  math(EXPR scaled "${i} * 102")
  math(EXPR whole "${scaled} / 100")
  math(EXPR frac "${scaled} % 100")
  if(frac LESS 10)
    set(frac "0${frac}")
  endif()
  string(APPEND gt "1 0 0 0 0 1 0 0 0 0 1 ${i}\n")
  string(APPEND est "1 0 0 0 0 1 0 0 0 0 1 ${whole}.${frac}\n")
endforeach()
file(WRITE ${WORK_DIR}/gt.txt "${gt}")
file(WRITE ${WORK_DIR}/est.txt "${est}")

execute_process(COMMAND ${RGBL} eval ${WORK_DIR}/est.txt ${WORK_DIR}/gt.txt --lengths 100,200 --json ${WORK_DIR}/eval.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbl eval failed with ${rc}")
endif()
foreach(expected
    "100 +90 +2\\.0200 +0\\.0000"
    "200 +80 +2\\.0100 +0\\.0000"
    "all +170 +2\\.0153 +0\\.0000"
    "ATE [^\n]*rmse 5\\.7793"
    "RPE per frame, translation [^\n]*rmse 0\\.0200 +mean 0\\.0200"
    "end-point drift: 20\\.0000 m = 2\\.0000 %"
    "path length: +1000\\.000 m \\(ground truth\\); the estimate's 1020\\.000 m")
  if(NOT out MATCHES "${expected}")
    message(FATAL_ERROR "output does not match '${expected}'")
  endif()
endforeach()
file(READ ${WORK_DIR}/eval.json json)
string(JSON segments GET "${json}" kitti segments)
string(JSON t_err GET "${json}" kitti per_length 0 t_err_percent)
string(JSON drift GET "${json}" drift percent)
if(NOT segments EQUAL 170 OR NOT t_err MATCHES "^2\\.02" OR NOT drift MATCHES "^(2|1\\.9999|2\\.0000)")
  message(FATAL_ERROR "JSON: segments ${segments}, t_err ${t_err}, drift ${drift}")
endif()

# TUM files: the estimate is stamped 5 ms later than the truth (associated within 20 ms) and shifted
# by a constant 0.5 m, which the rigid alignment removes: ATE 0, RPE 0, drift 0. Segments of 10 m start
# at frames 0..80 (9), of 50 m at 0..40 (5).
set(gt "# timestamp tx ty tz qx qy qz qw\n")
set(est "")
foreach(i RANGE 0 100)
  string(APPEND gt "${i}.000 ${i} 0 0 0 0 0 1\n")
  string(APPEND est "${i}.005 ${i}.5 0 0 0 0 0 1\n")
endforeach()
file(WRITE ${WORK_DIR}/gt_tum.txt "${gt}")
file(WRITE ${WORK_DIR}/est_tum.txt "${est}")
execute_process(COMMAND ${RGBL} eval ${WORK_DIR}/est_tum.txt ${WORK_DIR}/gt_tum.txt --lengths 10,50
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbl eval (TUM) failed with ${rc}")
endif()
foreach(expected "\\(tum, 101 poses\\)" "associated 101 of 101 estimated poses" "all +14 +0\\.0000 +0\\.0000"
                 "ATE [^\n]*rmse 0\\.0000 +mean 0\\.0000" "end-point drift: 0\\.0000 m")
  if(NOT out MATCHES "${expected}")
    message(FATAL_ERROR "output does not match '${expected}'")
  endif()
endforeach()

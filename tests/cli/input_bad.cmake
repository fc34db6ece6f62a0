# Bad input files and option values (issue 18): each must end in one "error: " line naming the file
# or the option (CLI11's "--option: ..." for option values), never a signal, a hang or a success.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
execute_process(COMMAND ${RGBL_SIM} --out ${WORK_DIR}/data --frames 4 --width 100 --height 60 --quiet
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbl_sim failed: ${out}${err}")
endif()
set(seq ${WORK_DIR}/data/sequences/00)

# expect(<regex of stderr> <rgbl arguments...>): exits 1 (2 for CLI11's option errors is fine too), in
# time, with the message; `error: ` lines are single.
function(expect expected)
  execute_process(COMMAND ${RGBL} --quiet ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                  TIMEOUT 60)
  message("rgbl ${ARGN}\n  exit ${rc}: ${err}")
  if(NOT rc MATCHES "^[0-9]+$")
    message(FATAL_ERROR "rgbl ${ARGN} ended with a signal or timed out: ${rc}")
  endif()
  if(rc EQUAL 0)
    message(FATAL_ERROR "rgbl ${ARGN} succeeded")
  endif()
  if(NOT err MATCHES "${expected}")
    message(FATAL_ERROR "the error lacks '${expected}'")
  endif()
  if(err MATCHES "^error: " AND NOT err MATCHES "^error: [^\n]*\n$")
    message(FATAL_ERROR "stderr is not exactly one 'error: ' line")
  endif()
  if(err MATCHES "terminate called|Aborted|what\\(\\)|OpenCV\\(|[0-9]{40}")
    message(FATAL_ERROR "looks like a crash, a raw library message or a 309-digit range")
  endif()
endfunction()

# counts and indices: negative, overflowing and zero used to mean "all frames" silently
expect("--frames: expected a whole number from 1 to 1000000000, found '-1'" run ${seq} --frames -1 --out ${WORK_DIR}/o)
expect("--frames: expected a whole number from 1 to 1000000000, found '18446744073709551616'" run ${seq} --frames
       18446744073709551616 --out ${WORK_DIR}/o)
expect("--frames: expected a whole number from 1" run ${seq} --frames 0 --out ${WORK_DIR}/o)
expect("--first: expected a whole number from 0" run ${seq} --first -1 --out ${WORK_DIR}/o)
expect("--step: expected a whole number from 1 to 1000000000, found '0'" run ${seq} --step 0 --out ${WORK_DIR}/o)
# eval's numeric options: no 309-digit range either
expect("--step: expected a whole number from 1 to 1000000000, found '0'" eval ${WORK_DIR}/e.txt ${WORK_DIR}/g.txt
       --step 0)
expect("--lengths: expected a finite number above 0, found '0'" eval ${WORK_DIR}/e.txt ${WORK_DIR}/g.txt
       --lengths 100,0)
expect("--max-dt: expected a finite number from 0, found 'nan'" eval ${WORK_DIR}/e.txt ${WORK_DIR}/g.txt
       --max-dt nan)

# stereo on images no wider than SGBM's disparity range aborted inside OpenCV (SIGABRT)
expect("^error: invalid option '--depth': expected stereo on images wider than its disparity range" run ${seq}
       --depth stereo --out ${WORK_DIR}/o)

# a settings file nested 50 000 deep overflowed the stack (SIGSEGV)
string(REPEAT "[" 50000 open)
string(REPEAT "]" 50000 close)
file(WRITE ${WORK_DIR}/deep.yaml "a: ${open}${close}\n")
expect("^error: [^\n]*deep\\.yaml:1: nested deeper than 64 levels" run ${seq} --config ${WORK_DIR}/deep.yaml --out
       ${WORK_DIR}/o)

# a FIFO as calib.txt blocked forever
file(COPY ${seq}/ DESTINATION ${WORK_DIR}/fifo)
file(REMOVE ${WORK_DIR}/fifo/calib.txt)
execute_process(COMMAND mkfifo ${WORK_DIR}/fifo/calib.txt RESULT_VARIABLE rc)
if(rc EQUAL 0)
  expect("^error: [^\n]*fifo/calib\\.txt: is not a regular file" info ${WORK_DIR}/fifo)
endif()

# calibration: focal lengths of 1e-300 gave -nan trajectories with exit 0; a zero Tr was accepted
file(READ ${seq}/calib.txt calib)
string(REGEX REPLACE "P0: [^ ]+ ([^ ]+ [^ ]+ [^ ]+ [^ ]+) [^ ]+" "P0: 1e-300 \\1 1e-300" tiny "${calib}")
file(COPY ${seq}/ DESTINATION ${WORK_DIR}/tiny)
file(WRITE ${WORK_DIR}/tiny/calib.txt "${tiny}")
expect("^error: [^\n]*tiny/calib\\.txt:1: 'P0': focal lengths fx 1e-300 fy 1e-300" run ${WORK_DIR}/tiny --out
       ${WORK_DIR}/o)
string(REGEX REPLACE "Tr: [^\n]*" "Tr: 0 0 0 0 0 0 0 0 0 0 0 0" zero "${calib}")
file(COPY ${seq}/ DESTINATION ${WORK_DIR}/zero)
file(WRITE ${WORK_DIR}/zero/calib.txt "${zero}")
expect("^error: [^\n]*zero/calib\\.txt:5: expected 'Tr' to hold a rotation matrix" info ${WORK_DIR}/zero --check)

# times.txt with a repeated time
file(COPY ${seq}/ DESTINATION ${WORK_DIR}/times)
file(WRITE ${WORK_DIR}/times/times.txt "0\n0.1\n0.1\n0.3\n")
expect("^error: [^\n]*times/times\\.txt:3: timestamp 0\\.1 is not after the one on line 2" run ${WORK_DIR}/times
       --out ${WORK_DIR}/o)

# info --check lists every bad file, not only the first
file(COPY ${seq}/ DESTINATION ${WORK_DIR}/check)
file(WRITE ${WORK_DIR}/check/image_0/000001.png "not a PNG")
file(WRITE ${WORK_DIR}/check/velodyne/000002.bin "twenty bytes of junk")
execute_process(COMMAND ${RGBL} --quiet info ${WORK_DIR}/check --check RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err TIMEOUT 60)
message("rgbl info --check\n  exit ${rc}: ${out}${err}")
if(NOT rc EQUAL 1 OR NOT out MATCHES "frame 1: [^\n]*000001\\.png" OR NOT out MATCHES "frame 2: [^\n]*000002\\.bin"
   OR NOT err MATCHES "^error: [^\n]*2 file\\(s\\) of 2 of the 4 frames do not load")
  message(FATAL_ERROR "rgbl info --check does not list both bad files")
endif()

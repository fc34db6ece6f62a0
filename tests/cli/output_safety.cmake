# Issue 18, the output side: rgbl never overwrites or replaces what it was not asked to, and never
# reports success for output that did not arrive.
#  - demo --keep refuses a folder that holds files (it overwrote a KITTI root's sequences/00, poses/00.txt);
#  - eval --json writes through a device node, a FIFO and a symlink instead of replacing them;
#  - eval reads each input once (a pipe works);
#  - a full stdout is an error;
#  - a second run into an output folder that is being written is refused, and removes nothing there.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

function(expect_failure expected)
  execute_process(COMMAND ${RGBL} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("rgbl ${ARGN}\n  exit ${rc}: ${err}")
  if(rc EQUAL 0)
    message(FATAL_ERROR "rgbl ${ARGN} succeeded")
  endif()
  if(NOT err MATCHES "error: [^\n]*${expected}")
    message(FATAL_ERROR "the error lacks '${expected}'")
  endif()
endfunction()

function(expect_success)
  execute_process(COMMAND ${RGBL} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "rgbl ${ARGN} failed (${rc}): ${out}${err}")
  endif()
endfunction()

# --- demo --keep on a folder holding a KITTI root
set(keep ${WORK_DIR}/k)
file(WRITE ${keep}/sequences/00/times.txt "precious\n")
file(WRITE ${keep}/poses/00.txt "precious poses\n")
expect_failure("invalid option '--keep': expected a new or empty folder" --quiet demo --frames 5 --path straight
               --keep ${keep} --out ${WORK_DIR}/demo_out)
file(READ ${keep}/sequences/00/times.txt times)
file(READ ${keep}/poses/00.txt poses)
if(NOT times STREQUAL "precious\n" OR NOT poses STREQUAL "precious poses\n")
  message(FATAL_ERROR "demo --keep changed the files of the folder it refused")
endif()
file(GLOB kept RELATIVE ${keep} ${keep}/*)
if(NOT kept STREQUAL "poses;sequences")
  message(FATAL_ERROR "demo --keep added files to the folder it refused: ${kept}")
endif()

# --- eval --json into special files
set(row0 "1 0 0 0 0 1 0 0 0 0 1 0\n")
file(WRITE ${WORK_DIR}/gt.txt "${row0}1 0 0 0 0 1 0 0 0 0 1 1\n1 0 0 0 0 1 0 0 0 0 1 2\n1 0 0 0 0 1 0 0 0 0 1 3\n")
file(WRITE ${WORK_DIR}/est.txt "${row0}1 0 0 0 0 1 0 0 0 0 1 1.1\n1 0 0 0 0 1 0 0 0 0 1 2\n1 0 0 0 0 1 0 0 0 0 1 3.2\n")
set(gt ${WORK_DIR}/gt.txt)
set(est ${WORK_DIR}/est.txt)

# a symlink: the file it points to is written, the link stays
file(WRITE ${WORK_DIR}/real.json "old\n")
file(CREATE_LINK real.json ${WORK_DIR}/link.json SYMBOLIC)
expect_success(eval ${est} ${gt} --json ${WORK_DIR}/link.json)
if(NOT IS_SYMLINK ${WORK_DIR}/link.json)
  message(FATAL_ERROR "eval --json replaced the symlink link.json by a file")
endif()
file(READ ${WORK_DIR}/real.json report)
if(NOT report MATCHES "\"ate_m\"")
  message(FATAL_ERROR "eval --json through a symlink did not write the file it points to: ${report}")
endif()

# a device node (/dev/null's numbers; as root, else a link to /dev/null)
execute_process(COMMAND mknod -m 666 ${WORK_DIR}/null c 1 3 RESULT_VARIABLE rc ERROR_QUIET)
if(NOT rc EQUAL 0)
  file(CREATE_LINK /dev/null ${WORK_DIR}/null SYMBOLIC)
endif()
expect_success(eval ${est} ${gt} --json ${WORK_DIR}/null)
execute_process(COMMAND test -c ${WORK_DIR}/null RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "eval --json replaced the device node by a regular file")
endif()

# a FIFO without a reader: an error instead of a wait, and the FIFO stays
execute_process(COMMAND mkfifo ${WORK_DIR}/fifo RESULT_VARIABLE rc)
if(rc EQUAL 0)
  expect_failure("fifo: a FIFO with no reader" eval ${est} ${gt} --json ${WORK_DIR}/fifo)
  execute_process(COMMAND test -p ${WORK_DIR}/fifo RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "eval --json replaced the FIFO by a regular file")
  endif()
endif()
file(GLOB parts ${WORK_DIR}/*.part)
if(parts)
  message(FATAL_ERROR "left-over partial files: ${parts}")
endif()

# --- an input read once: the estimate from a pipe
execute_process(COMMAND cat ${est} COMMAND ${RGBL} eval /dev/stdin ${gt} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "kitti, 4 poses")
  message(FATAL_ERROR "eval of an estimate from a pipe failed (${rc}): ${out}${err}")
endif()

# --- stdout that cannot be written
if(EXISTS /dev/full)
  execute_process(COMMAND ${RGBL} eval ${est} ${gt} OUTPUT_FILE /dev/full RESULT_VARIABLE rc ERROR_VARIABLE err)
  message("rgbl eval > /dev/full\n  exit ${rc}: ${err}")
  if(rc EQUAL 0 OR NOT err MATCHES "error: cannot write to standard output")
    message(FATAL_ERROR "a failed write to stdout was not reported")
  endif()
endif()

# --- an output folder another process writes into (held here by flock(1) on the folder)
find_program(FLOCK flock)
if(FLOCK)
  execute_process(COMMAND ${RGBL_SIM} --out ${WORK_DIR}/data --frames 6 --width 306 --height 92 --quiet
                  RESULT_VARIABLE rc OUTPUT_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "rgbl_sim failed")
  endif()
  set(out_dir ${WORK_DIR}/out)
  expect_success(--quiet run ${WORK_DIR}/data/sequences/00 --out ${out_dir})
  # a second run, and rgbl depth (the same lock), into the folder another process holds: refused
  # before they remove or write anything there
  foreach(command run depth)
    execute_process(COMMAND ${FLOCK} ${out_dir} ${RGBL} --quiet ${command} ${WORK_DIR}/data/sequences/00 --out ${out_dir}
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    message("rgbl ${command} into a locked folder\n  exit ${rc}: ${err}")
    if(rc EQUAL 0 OR NOT err MATCHES "error: [^\n]*out: another rgbl process is writing into this output folder")
      message(FATAL_ERROR "rgbl ${command} into a folder being written was not refused")
    endif()
    if(NOT EXISTS ${out_dir}/trajectory_kitti.txt OR NOT EXISTS ${out_dir}/summary.json OR EXISTS ${out_dir}/depth)
      message(FATAL_ERROR "the refused rgbl ${command} changed the folder another process writes into")
    endif()
  endforeach()
  expect_success(--quiet depth ${WORK_DIR}/data/sequences/00 --out ${out_dir})
  file(GLOB left ${out_dir}/depth/*.part ${out_dir}/preview/*.part)
  file(GLOB maps ${out_dir}/depth/*.png)
  list(LENGTH maps n_maps)
  if(left OR NOT n_maps EQUAL 6)
    message(FATAL_ERROR "rgbl depth: expected 6 maps and no temporary files, got ${n_maps} maps, left: ${left}")
  endif()
  # and an unwritable --out is refused before the run
  file(WRITE ${WORK_DIR}/a_file "x")
  expect_failure("a_file/out: cannot create the output folder" --quiet run ${WORK_DIR}/data/sequences/00 --out
                 ${WORK_DIR}/a_file/out)
endif()

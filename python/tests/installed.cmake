# `cmake --install` of the python component into a fresh prefix puts the package where the interpreter
# finds it (RGBL_PYTHON_INSTALL_DIR below the prefix), and that copy imports and works without the build tree.
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix --component python
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install --component python failed:\n${out}")
endif()
set(site ${WORK_DIR}/prefix/${INSTALL_DIR})
foreach(f _rgbl${EXT_SUFFIX} __init__.py __init__.pyi py.typed)
  if(NOT EXISTS ${site}/rgbl/${f})
    message(FATAL_ERROR "not installed: ${site}/rgbl/${f}")
  endif()
endforeach()
set(check "import rgbl, numpy as np, pathlib; \
assert pathlib.Path(rgbl.__file__).parent == pathlib.Path('${site}/rgbl'), rgbl.__file__; \
sparse = np.zeros((9, 9), np.float32); sparse[4, 4] = 7.0; \
assert np.count_nonzero(rgbl.dilate_depth(sparse)) == 13; \
print('installed rgbl', rgbl.__version__, 'from', rgbl.__file__)")
# run from the work folder: python -c puts the current folder first on sys.path
execute_process(COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${site} ${PYTHON} -c "${check}"
                WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
message("${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the installed package does not import")
endif()

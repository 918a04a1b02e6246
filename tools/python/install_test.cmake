# python.installs: `cmake --install --component python` into a fresh prefix, then Debian's python3,
# run from another folder with only that prefix's package folder on its path, imports limber and
# steps a scene. Fails when the install misses a file the package needs.
file(REMOVE_RECURSE ${PREFIX})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --component python --prefix ${PREFIX} RESULT_VARIABLE result)
if(result)
  message(FATAL_ERROR "cmake --install --component python failed: ${result}")
endif()
set(check "import limber, limber.sweep; w = limber.World(limber.load_scene('${SCENE}'), 'featherstone'); assert w.step() == 'ok'; print(limber.__file__)")
execute_process(COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${PREFIX}/${PACKAGE_DIR} ${PYTHON} -c "${check}"
                WORKING_DIRECTORY ${PREFIX} RESULT_VARIABLE result OUTPUT_VARIABLE where)
if(result OR NOT where MATCHES "^${PREFIX}/")
  message(FATAL_ERROR "the installed package did not import from ${PREFIX}/${PACKAGE_DIR}: ${result} ${where}")
endif()

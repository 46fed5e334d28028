# The consumer test (ctest embed_consumer): installs this build into a fresh prefix, builds the external
# project tests/embed/consumer against the installed package only, runs its two programs, and imports the
# installed Python module from the prefix (when the module is built), then has OpenImageIO's iinfo load the
# installed stex.imageio.so (OIIO_LIBRARY_PATH=<prefix>/<libdir>/stex/imageio, docs/oiio-plugin.md).
# Run: cmake -DBUILD_DIR= -DCONSUMER_DIR= -DWORK_DIR= -DEXEMPLAR= -DC_COMPILER= -DCXX_COMPILER= [-DPYTHON=]
#      -P consumer_test.cmake
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "failed (${rc}): ${cmd}\n${out}\n${err}")
  endif()
  set(run_output "${out}" PARENT_SCOPE)
endfunction()

set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})
foreach(component Runtime Development Python)
  run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix} --component ${component})
endforeach()
file(GLOB_RECURSE installed RELATIVE ${prefix} ${prefix}/*)
message(STATUS "installed: ${installed}")

run(${CMAKE_COMMAND} -S ${CONSUMER_DIR} -B ${WORK_DIR}/build -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_C_COMPILER=${C_COMPILER} -DCMAKE_CXX_COMPILER=${CXX_COMPILER})
string(REGEX MATCH "stex_DIR=[^\n]*" found "${run_output}")
message(STATUS "${found}")
if(NOT found MATCHES "^stex_DIR=${prefix}/")
  message(FATAL_ERROR "the consumer found stex outside the install prefix: ${found}")
endif()
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/consumer_app ${EXEMPLAR})
message(STATUS "${run_output}")
run(${WORK_DIR}/build/consumer_app_c)
message(STATUS "${run_output}")

# The OIIO plugin, from the prefix: a model made by this build's stex opens as an image.
file(GLOB_RECURSE plugins ${prefix}/*stex.imageio.so)
list(LENGTH plugins n)
if(NOT n EQUAL 1)
  message(FATAL_ERROR "expected one installed stex.imageio.so under ${prefix}, found: ${plugins}")
endif()
get_filename_component(plugin_dir ${plugins} DIRECTORY)
run(${BUILD_DIR}/cli/stex -q analyze ${EXEMPLAR} -o ${WORK_DIR}/m.stex --support 8 --iterations 2)
run(${CMAKE_COMMAND} -E env OIIO_LIBRARY_PATH=${plugin_dir} iinfo -v "${WORK_DIR}/m.stex?RES=96x64&TILE=32&SEED=4")
if(NOT run_output MATCHES "96 x +64, 1 channel, float stex" OR NOT run_output MATCHES "stex:seed: \"4\"")
  message(FATAL_ERROR "iinfo did not read the model through the installed plugin:\n${run_output}")
endif()
message(STATUS "installed plugin: ${plugin_dir}")

if(PYTHON)
  file(GLOB_RECURSE modules ${prefix}/stex*.so)
  list(FILTER modules EXCLUDE REGEX "/libstex|/stex\\.imageio\\.so$")
  list(LENGTH modules n)
  if(NOT n EQUAL 1)
    message(FATAL_ERROR "expected one installed Python module under ${prefix}, found: ${modules}")
  endif()
  get_filename_component(module_dir ${modules} DIRECTORY)
  # No LD_LIBRARY_PATH: the module must find the installed libstex.so through its RPATH.
  run(${CMAKE_COMMAND} -E env --unset=LD_LIBRARY_PATH PYTHONPATH=${module_dir} PYTHONDONTWRITEBYTECODE=1 ${PYTHON}
      ${CONSUMER_DIR}/check_module.py ${prefix} ${EXEMPLAR})
  message(STATUS "${run_output}")
endif()

# The kernel's folders in layers: a folder may include only folders listed before it, so the
# includes between folders point one way and form no cycle; kernel/README.md explains the order.
# Run as: cmake -DSOURCE_DIR=<repository> -P include_layers.cmake
set(layers
  numerics threading model mass geometry scene  # maths and descriptions, no state
  particles rigid                               # the two kinds of state: particles, rigid bodies
  sleeping relaxation collision                 # passes over that state
  verlet springs lagrange featherstone          # the four methods: compile and step
  methods                                       # the one dispatch over the four
  metrics world study)                          # what reads or drives the methods: the studies step a World

file(GLOB folders LIST_DIRECTORIES true RELATIVE ${SOURCE_DIR}/kernel ${SOURCE_DIR}/kernel/*)
set(problems "")
foreach(folder ${folders})
  if(NOT IS_DIRECTORY ${SOURCE_DIR}/kernel/${folder})
    continue()
  endif()
  list(FIND layers ${folder} rank)
  if(rank EQUAL -1)
    string(APPEND problems "kernel/${folder}/ is in no layer of tests/structure/include_layers.cmake\n")
    continue()
  endif()
  file(GLOB_RECURSE sources ${SOURCE_DIR}/kernel/${folder}/*.hpp ${SOURCE_DIR}/kernel/${folder}/*.cpp)
  foreach(source ${sources})
    file(STRINGS ${source} includes REGEX "^#include \"limber/kernel/[a-z_]+/")
    foreach(line ${includes})
      string(REGEX REPLACE "^#include \"limber/kernel/([a-z_]+)/.*" "\\1" target "${line}")
      if(target STREQUAL folder)
        continue()
      endif()
      list(FIND layers ${target} target_rank)
      if(target_rank GREATER_EQUAL rank OR target_rank EQUAL -1)
        file(RELATIVE_PATH shown ${SOURCE_DIR} ${source})
        string(APPEND problems "${shown}: includes kernel/${target}/, which is not below kernel/${folder}/\n")
      endif()
    endforeach()
  endforeach()
endforeach()
if(problems)
  message(FATAL_ERROR "Kernel folders include upwards:\n${problems}")
endif()

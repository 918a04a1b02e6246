# bench/peers/peers.cmake: the other engines the peer benchmarks run on limber's workloads —
# Bullet 3 (bullet.cmake), ODE 0.16 and MuJoCo 2.2.2, as Debian packages them (libbullet-dev,
# libode-dev, libmujoco-dev; tools/setup.sh installs them).
#   include(${PROJECT_SOURCE_DIR}/bench/peers/peers.cmake)
#   limber_link_peers(my_bench)   # adds each found peer's sources (bench/peers/*_chain.cpp) and library
# Found: INTERFACE targets limber_peer_bullet, limber_peer_ode, limber_peer_mujoco, each with its
# headers, libraries and compile definition (LIMBER_HAVE_BULLET, LIMBER_HAVE_ODE,
# LIMBER_HAVE_MUJOCO). Not found: a status message, and the benchmarks leave that engine out.
# LIMBER_PEERS=OFF looks for none of them.
include_guard(GLOBAL)

option(LIMBER_PEERS "Run other engines (Bullet, ODE, MuJoCo) in the peer benchmarks when they are installed" ON)

if(LIMBER_PEERS)
  include(${CMAKE_CURRENT_LIST_DIR}/bullet.cmake)

  # ODE. Its headers are shared by the single- and double-precision builds and select dReal from
  # ode/precision.h, which the package writes for the build it ships (Debian 12: dDOUBLE, also
  # pkg-config's "precision=dDOUBLE"); a user defining dSINGLE against a double library would
  # silently corrupt every dReal, so nothing is defined here and the header decides.
  # (ode_chain.cpp reports which one was compiled.)
  find_path(LIMBER_ODE_INCLUDE_DIR ode/ode.h)
  find_library(LIMBER_ODE_LIBRARY NAMES ode)
  if(LIMBER_ODE_INCLUDE_DIR AND LIMBER_ODE_LIBRARY)
    add_library(limber_peer_ode INTERFACE)
    target_include_directories(limber_peer_ode SYSTEM INTERFACE ${LIMBER_ODE_INCLUDE_DIR})
    target_link_libraries(limber_peer_ode INTERFACE ${LIMBER_ODE_LIBRARY})
    target_compile_definitions(limber_peer_ode INTERFACE LIMBER_HAVE_ODE)
    message(STATUS "ODE found (${LIMBER_ODE_LIBRARY}): peer benchmarks run it")
  else()
    message(STATUS "ODE not found (Debian: libode-dev): peer benchmarks skip it")
  endif()

  # MuJoCo. Not find_package(mujoco): Debian's config file points at an include directory it does
  # not ship (as in tests/CMakeLists.txt).
  find_path(LIMBER_MUJOCO_INCLUDE_DIR mujoco/mujoco.h)
  find_library(LIMBER_MUJOCO_LIBRARY NAMES mujoco)
  if(LIMBER_MUJOCO_INCLUDE_DIR AND LIMBER_MUJOCO_LIBRARY)
    add_library(limber_peer_mujoco INTERFACE)
    target_include_directories(limber_peer_mujoco SYSTEM INTERFACE ${LIMBER_MUJOCO_INCLUDE_DIR})
    target_link_libraries(limber_peer_mujoco INTERFACE ${LIMBER_MUJOCO_LIBRARY})
    target_compile_definitions(limber_peer_mujoco INTERFACE LIMBER_HAVE_MUJOCO)
    message(STATUS "MuJoCo found (${LIMBER_MUJOCO_LIBRARY}): peer benchmarks run it")
  else()
    message(STATUS "MuJoCo not found (Debian: libmujoco-dev): peer benchmarks skip it")
  endif()
else()
  message(STATUS "LIMBER_PEERS is OFF: peer benchmarks run limber only")
endif()

# Adds to `target` the chain of every peer found: its source and its library.
function(limber_link_peers target)
  set(_peers_directory ${PROJECT_SOURCE_DIR}/bench/peers)
  if(TARGET limber_peer_bullet)
    target_sources(${target} PRIVATE ${_peers_directory}/bullet_chain.cpp ${_peers_directory}/bullet_rigid_chain.cpp)
    target_link_libraries(${target} PRIVATE limber_peer_bullet)
  endif()
  if(TARGET limber_peer_ode)
    target_sources(${target} PRIVATE ${_peers_directory}/ode_chain.cpp)
    target_link_libraries(${target} PRIVATE limber_peer_ode)
  endif()
  if(TARGET limber_peer_mujoco)
    target_sources(${target} PRIVATE ${_peers_directory}/mujoco_chain.cpp)
    target_link_libraries(${target} PRIVATE limber_peer_mujoco)
  endif()
endfunction()

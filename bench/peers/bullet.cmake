# bench/peers/bullet.cmake: Bullet 3 (Debian's libbullet-dev) for the peer-engine benchmarks.
#   include(${PROJECT_SOURCE_DIR}/bench/peers/bullet.cmake)
#   if(TARGET limber_peer_bullet)
#     target_sources(my_bench PRIVATE ${PROJECT_SOURCE_DIR}/bench/peers/bullet_chain.cpp)
#     target_link_libraries(my_bench PRIVATE limber_peer_bullet)   # and limber::limber, whose
#   endif()                                                         # include path bullet_chain.cpp uses
# Found: the INTERFACE target limber_peer_bullet (headers, BulletDynamics, BulletCollision,
# LinearMath, and the compile definition LIMBER_HAVE_BULLET). Not found: a status message only.
#
# Debian installs two builds side by side: single precision (libBulletDynamics.so, ...) and double
# (libBulletDynamics-float64.so, ..., whose users must define BT_USE_DOUBLE_PRECISION). The shared
# headers cannot tell them apart, and a mismatch silently corrupts every btScalar, so the library
# names and the definition are chosen together here. Debian's BulletConfig.cmake is not used: its
# paths are relative ("include/bullet") and it lists BulletInverseDynamics, which is not shipped.
include_guard(GLOBAL)

option(LIMBER_BULLET_DOUBLE_PRECISION "Use Bullet's double-precision build (the -float64 libraries)" OFF)
if(LIMBER_BULLET_DOUBLE_PRECISION)
  set(_limber_bullet_precision double)
  set(_limber_bullet_suffix -float64)
else()
  set(_limber_bullet_precision single)
  set(_limber_bullet_suffix "")
endif()

find_path(LIMBER_BULLET_INCLUDE_DIR BulletDynamics/Featherstone/btMultiBody.h PATH_SUFFIXES bullet)
# One cache entry per precision, so switching the option never reuses the other build's library.
set(_limber_bullet_libraries "")
foreach(_limber_bullet_component IN ITEMS BulletDynamics BulletCollision LinearMath)
  set(_limber_bullet_variable LIMBER_BULLET_${_limber_bullet_component}_${_limber_bullet_precision}_LIBRARY)
  find_library(${_limber_bullet_variable} NAMES ${_limber_bullet_component}${_limber_bullet_suffix})
  list(APPEND _limber_bullet_libraries ${${_limber_bullet_variable}})
endforeach()

if(LIMBER_BULLET_INCLUDE_DIR AND NOT _limber_bullet_libraries MATCHES "NOTFOUND")
  add_library(limber_peer_bullet INTERFACE)
  # SYSTEM: Bullet's headers are not clean under -Wall -Wextra -Wpedantic.
  target_include_directories(limber_peer_bullet SYSTEM INTERFACE ${LIMBER_BULLET_INCLUDE_DIR})
  target_link_libraries(limber_peer_bullet INTERFACE ${_limber_bullet_libraries})
  target_compile_definitions(limber_peer_bullet INTERFACE LIMBER_HAVE_BULLET
                             $<$<BOOL:${LIMBER_BULLET_DOUBLE_PRECISION}>:BT_USE_DOUBLE_PRECISION>)
  message(STATUS "Bullet (${_limber_bullet_precision} precision) found: peer benchmarks enabled")
else()
  message(STATUS "Bullet (${_limber_bullet_precision} precision) not found (Debian: libbullet-dev): "
                 "peer benchmarks skip it")
endif()

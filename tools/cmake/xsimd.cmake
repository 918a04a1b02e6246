# xsimd, as Debian 12 packages it (libxsimd-dev 8.1): its config links a bare `xtl` target it
# never defines. xtl is header-only, so an empty interface target satisfies it (otherwise every
# executable fails to link with -lxtl). Used by the project and by the installed limberConfig.cmake.
if(NOT TARGET xtl)
  add_library(xtl INTERFACE IMPORTED)
endif()
find_package(xsimd 8 REQUIRED)

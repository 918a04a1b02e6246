# The install rules and the CMake package: after `cmake --install`, an engine's
#   find_package(limber 0.2 CONFIG REQUIRED)
#   target_link_libraries(engine PRIVATE limber::limber)
# gets the library, the headers as <limber/kernel/...> and <limber/layouts/...>, its public
# dependencies (Eigen, oneTBB, xsimd) and the instruction set it was built for.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(LIMBER_PACKAGE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/limber)
install(TARGETS limber EXPORT limberTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
foreach(folder kernel layouts)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${folder}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/limber/${folder}
          FILES_MATCHING PATTERN "*.hpp" PATTERN "*.md" PATTERN "kernel/limber.hpp" EXCLUDE)
endforeach()
install(FILES ${LIMBER_INCLUDE_DIR}/limber/config.hpp ${PROJECT_SOURCE_DIR}/kernel/limber.hpp DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/limber)
install(EXPORT limberTargets NAMESPACE limber:: DESTINATION ${LIMBER_PACKAGE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/tools/cmake/limberConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/limberConfig.cmake INSTALL_DESTINATION ${LIMBER_PACKAGE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/limberConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/limberConfig.cmake ${PROJECT_BINARY_DIR}/limberConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/tools/cmake/xsimd.cmake
        DESTINATION ${LIMBER_PACKAGE_DIR})
if(TARGET limber_program)
  install(TARGETS limber_program RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

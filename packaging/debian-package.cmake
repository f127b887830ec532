# `cpack -G DEB` in a build folder makes jointcomp_<version>_<arch>.deb: the command-line tool with its
# plot scripts, robots, parameter files and FMUs, the shared library with its header, CMake package and
# pkg-config file, and the Python package where Debian's python3 finds it. Installed under /usr, so the
# library is on the loader's path and nothing needs LD_LIBRARY_PATH. The package's dependencies are the
# Debian libraries the binaries link (dpkg-shlibdeps) and the Python modules the bindings and plots use.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME jointcomp)
set(CPACK_PACKAGE_VENDOR "the jointcomp authors")
set(CPACK_PACKAGE_CONTACT "jointcomp maintainers <jointcomp@users.noreply.github.com>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_RESOURCE_FILE_LICENSE "${PROJECT_SOURCE_DIR}/LICENSE")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "python3, python3-numpy")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3-matplotlib, python3-distributed")
# One package with every component (the library, the tool, its data, the FMUs, the bindings).
set(CPACK_DEB_COMPONENT_INSTALL OFF)
set(CPACK_STRIP_FILES ON)
include(CPack)

# FindSLEEF: locate SLEEF (vectorised libm; Debian: libsleef-dev) and provide SLEEF::SLEEF.
# Debian ships a sleef.pc but no CMake package; the header lies in the multiarch include folder
# (cmake/ColocFindImported.cmake).
include(ColocFindImported)
coloc_find_imported(SLEEF sleef.h sleef)

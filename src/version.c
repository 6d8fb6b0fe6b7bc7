/* version.c — mr_version(). */
#include "matremap.h"

const char *mr_version(void) { return MR_VERSION_STRING; }

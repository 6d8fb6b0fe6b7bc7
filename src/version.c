/* version.c — mr_version(). */
#include "mr_core.h"

const char *mr_version(void) { return MR_VERSION_STRING; }

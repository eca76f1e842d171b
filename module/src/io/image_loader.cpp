// (being written)
#include "ridgeline/io.h"

/* The one header bindgen reads. Embree's public API is all in rtcore.h. */
#include <embree3/rtcore.h>

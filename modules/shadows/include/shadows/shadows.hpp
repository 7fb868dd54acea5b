#pragma once
// The shadow module's public API: settings and statistics (shadows/settings.hpp) and the context a
// host creates on its own Vulkan device and records into its own command buffers
// (shadows/context.hpp). Only Vulkan and the standard library appear in these headers.
#include "shadows/context.hpp"
#include "shadows/settings.hpp"

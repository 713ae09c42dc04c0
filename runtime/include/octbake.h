// Everything an app needs: include this one header and link octbake::runtime.
#pragma once
#include "octbake/baked_file.h"
#include "octbake/collide.h"
#include "octbake/collision_world.h"
#include "octbake/level_cache.h"
#include "octbake/lod.h"
#include "octbake/motion.h"
#include "octbake/object_tree.h"
#include "octbake/pose.h"
#include "octbake/result.h"
#include "octbake/version.h"
#include "octbake/world.h"
#include "octbake/world_tree.h"

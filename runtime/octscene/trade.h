// `octscene trade SCENE [options]`: the speed/accuracy trade of every LOD
// setting against an exact mesh-mesh answer. Parses its own arguments
// (argv[0] == "trade"); returns the exit status.
#pragma once

namespace octbake::scene {
int trade_main(int argc, char** argv);
}

// `octscene picture ...`: PNG pictures of ObjectTrees and scene frames.
// Parses its own arguments (argv[0] == "picture"); returns the exit status.
#pragma once

namespace octbake::scene {
int picture_main(int argc, char** argv);
}

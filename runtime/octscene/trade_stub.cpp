// Placeholder until trade.cpp / picture.cpp land (then this file is deleted).
#include <cstdio>

#include "picture.h"
#include "trade.h"

namespace octbake::scene {
int trade_main(int, char**) { std::fputs("octscene: trade not built yet\n", stderr); return 2; }
int picture_main(int, char**) { std::fputs("octscene: picture not built yet\n", stderr); return 2; }
}  // namespace octbake::scene

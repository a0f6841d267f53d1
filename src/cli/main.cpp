// PLACEHOLDER: the welkin CLI lands with its own commit.
#include <cstdio>
int main() {
    std::fputs("welkin: the command-line tool is not built yet\n", stderr);
    return 2;
}

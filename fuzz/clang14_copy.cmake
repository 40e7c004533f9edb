# cmake -DIN=schedule_import.cpp -DOUT=copy.cpp -P clang14_copy.cmake
# The copy clang < 16 compiles: the one structured binding a lambda captures, spelt out.
file(READ ${IN} text)
string(REPLACE "for (const auto& [node, key] : m_options.groupSignals) {"
               "for (const auto& nodeKey : m_options.groupSignals) { const auto& node = nodeKey.first; const auto& key = nodeKey.second;"
               text "${text}")
file(WRITE ${OUT} "${text}")

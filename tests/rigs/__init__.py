"""Tests of cgaskin.rigs: glTF and assimp loading, export, the procedural arm."""

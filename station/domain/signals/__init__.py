"""The signals: samples, stillness, poses and orientation."""

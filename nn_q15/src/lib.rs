//! The embedded learner (work in progress).
#![no_std]

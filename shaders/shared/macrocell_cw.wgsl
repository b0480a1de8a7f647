// The macrocell kernel's walk with the Cleary-Wyvill walker: the nested walk (macro grid, then each
// occupied macrocell's fine cells).
//!include shared/macrocell_nested.wgsl

//! Files a render writes and reads back: PNG/EXR images, film files, and shards of one render.

pub mod film_file;
pub mod output;
pub mod shard;

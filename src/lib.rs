pub mod hit;
pub mod scene;
pub mod texture;

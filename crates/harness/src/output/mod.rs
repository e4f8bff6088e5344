//! What raybench shows to people: the tables commands print, the agreement sentence, the
//! Markdown results page, the replay text, scene previews, and the charts, pictures and HTML
//! page drawn from a report.

pub mod agreement;
pub mod compare_table;
pub mod history;
pub mod png;
pub mod preview;
pub mod render;
pub mod replay_text;
pub mod results;
pub mod summary;
pub mod verify_table;
pub mod watertight_table;
pub mod work_per_ray;

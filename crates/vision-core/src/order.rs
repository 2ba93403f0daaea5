//! The order of the frames of an image folder.

use std::path::PathBuf;

/// Sorts frame files in natural order of their file names: runs of digits compare by value, so
/// `2.png` comes before `10.png` (as image viewers and ffmpeg's `%d` patterns number frames), and
/// zero-padded names (`0001.png`) keep their order. Uses the `alphanumeric-sort` crate, which
/// compares names that are not UTF-8 too. The `track` command line and the library's examples
/// read folders in this order.
///
/// # Examples
/// ```
/// use std::path::PathBuf;
///
/// let mut frames: Vec<PathBuf> = ["f10.png", "f2.png", "f1.png"].map(PathBuf::from).into();
/// vision_core::sort_natural(&mut frames);
/// assert_eq!(frames, ["f1.png", "f2.png", "f10.png"].map(PathBuf::from));
/// ```
pub fn sort_natural(paths: &mut [PathBuf]) {
    alphanumeric_sort::sort_slice_by_os_str_key(paths, |p: &PathBuf| {
        p.file_name().unwrap_or(p.as_os_str())
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digits_compare_by_value_and_folders_do_not_matter() {
        let mut paths: Vec<PathBuf> = ["b/10.png", "a/9.png", "c/0011.png", "d/1.png"]
            .map(PathBuf::from)
            .into();
        sort_natural(&mut paths);
        assert_eq!(
            paths,
            ["d/1.png", "a/9.png", "b/10.png", "c/0011.png"].map(PathBuf::from)
        );
        // A plain sort would put "10" before "9".
        let mut plain: Vec<PathBuf> = ["9.png", "10.png"].map(PathBuf::from).into();
        plain.sort();
        assert_eq!(plain[0], PathBuf::from("10.png"));
        sort_natural(&mut plain);
        assert_eq!(plain[0], PathBuf::from("9.png"));
    }
}

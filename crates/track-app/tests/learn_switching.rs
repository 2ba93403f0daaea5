//! Learning the switching parameters by EM on smoothed runs: on a long synthetic
//! sequence the learnt T_β matches the transition frequencies of the generator's true β sequence.

use crate::common;

use scene_synth::Scenario;
use track_app::evaluation::SyntheticSequence;
use trackers::{ClutterMode, Preset, SmootherSettings, SwitchingStatistics};

/// The frequencies of the true class transitions, row-normalised.
fn true_frequencies(seq: &SyntheticSequence) -> Vec<Vec<f64>> {
    let mut counts = vec![vec![0.0; 3]; 3];
    for pair in seq.truth.windows(2) {
        let (a, b) = (pair[0].clutter_class, pair[1].clutter_class);
        counts[usize::from(a) - 1][usize::from(b) - 1] += 1.0;
    }
    counts
        .into_iter()
        .map(|row| {
            let total: f64 = row.iter().sum();
            row.into_iter().map(|x| x / total).collect()
        })
        .collect()
}

#[test]
fn the_learnt_clutter_transitions_match_the_generators_frequencies() {
    // Two texture draws of a 400-frame scene: the target crosses the three clutter bands.
    let scenes: Vec<_> = [3, 4]
        .iter()
        .map(|&seed| SyntheticSequence::render(Scenario::Mclutter, Some(400), seed, &[]).unwrap())
        .collect();
    let truth = true_frequencies(&scenes[0]);
    let mut config = Preset::WHmm.config(150, 1);
    for _iteration in 0..2 {
        let mut total = SwitchingStatistics::default();
        for seq in &scenes {
            let (_, _, stats) = seq
                .track_and_smooth(config.clone(), &SmootherSettings::default())
                .unwrap();
            total.add(&stats);
        }
        total.maximise(&mut config, false).unwrap();
    }
    let ClutterMode::Switching(clutter) = &config.clutter else {
        panic!("w-hmm switches clutter");
    };
    for (learnt, true_row) in clutter.transition.iter().zip(&truth) {
        for (l, t) in learnt.iter().zip(true_row) {
            assert!(
                (l - t).abs() <= 0.05,
                "learnt {:?}\ntrue {truth:?}",
                clutter.transition
            );
        }
    }
    // The learnt configuration is valid and loads back from its JSON.
    let json = serde_json::to_string(&config).unwrap();
    let back: trackers::TrackerConfig = serde_json::from_str(&json).unwrap();
    back.validate().unwrap();
}

#[test]
fn learn_switching_writes_a_configuration_that_track_run_loads() {
    let dir = tempfile::tempdir().unwrap();
    let frames = common::disc_frames(dir.path(), "disc", 10);
    // An OTB folder: frames in img/ and a first box.
    let otb = dir.path().join("otb");
    std::fs::create_dir_all(otb.join("img")).unwrap();
    for entry in std::fs::read_dir(&frames).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), otb.join("img").join(entry.file_name())).unwrap();
    }
    let boxes = (0..10)
        .map(|k| format!("{},24,24,24\n", 18 + 2 * k))
        .collect::<String>();
    std::fs::write(otb.join("groundtruth_rect.txt"), boxes).unwrap();
    let learnt = dir.path().join("learnt.json");
    let o = common::track(&[
        "learn-switching",
        common::s(&otb),
        "--tracker",
        "w-eval",
        "--particles",
        "50",
        "--iterations",
        "2",
        "--quiet",
        "--out",
        common::s(&learnt),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let run = common::track(&[
        "run",
        "--config",
        common::s(&learnt),
        "--quiet",
        "--out",
        common::s(&dir.path().join("out")),
        common::s(&otb),
    ]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    // A tracker without switching processes is refused (exit 2).
    let m1 = common::track(&[
        "learn-switching",
        common::s(&otb),
        "--tracker",
        "m1",
        "--out",
        common::s(&dir.path().join("m1.json")),
    ]);
    assert_eq!(m1.status.code(), Some(2));
    assert!(!dir.path().join("m1.json").exists());
}

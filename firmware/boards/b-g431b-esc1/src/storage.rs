//! The node's configuration in flash (sequential-storage map in the last 4 KB):
//! every configuration the host commits over CAN is kept, and replayed into
//! the node after homing on the next start, through the same protocol frames
//! as the board's own (`Receiver::on_kept_frame`: not held to the ceiling
//! lock, which only ever let tighter or maintenance bounds reach the store).

use core::ops::Range;

use embassy_embedded_hal::adapter::BlockingAsync;
use embassy_stm32::flash::{Blocking, Flash};
use embassy_time::Timer;
use sequential_storage::cache::NoCache;
use sequential_storage::map::{fetch_item, store_item};
use triquint_firmware::RxFrame;
use triquint_shared::protocol::{
    Command, CommandCode, DriveConfig, PARAM_COUNT, config_write_frame,
};

use crate::can::RESTORE;
use crate::control::{TO_STORE, now_us};

pub type Storage = BlockingAsync<Flash<'static, Blocking>>;

/// Flash offsets of the map: the last two 2 KB pages of the 128 KB.
const RANGE: Range<u32> = 0x1F000..0x20000;
const KEY_NODE_ID: u8 = 1;
const KEY_CONFIG: u8 = 2;

/// Stored node id, if any.
pub async fn node_id(flash: &mut Storage) -> Option<u8> {
    let mut buf = [0u8; 32];
    fetch_item::<u8, u8, _>(flash, RANGE, &mut NoCache::new(), &mut buf, &KEY_NODE_ID)
        .await
        .ok()
        .flatten()
}

pub async fn store_node_id(flash: &mut Storage, id: u8) {
    let mut buf = [0u8; 32];
    let _ = store_item(
        flash,
        RANGE,
        &mut NoCache::new(),
        &mut buf,
        &KEY_NODE_ID,
        &id,
    )
    .await;
}

#[embassy_executor::task]
pub async fn keep(mut flash: Storage, node: u8) {
    let mut buf = [0u8; 4 * (PARAM_COUNT + 1) + 32];
    // Replay the kept configuration: writes, then the commit with its CRC.
    let kept = fetch_item::<u8, [u32; PARAM_COUNT + 1], _>(
        &mut flash,
        RANGE,
        &mut NoCache::new(),
        &mut buf,
        &KEY_CONFIG,
    )
    .await;
    if let Ok(Some(words)) = kept {
        for (i, w) in words.iter().take(PARAM_COUNT).enumerate() {
            let frame = config_write_frame(node, i as u8, f32::from_bits(*w));
            RESTORE
                .send(RxFrame {
                    frame,
                    timestamp_us: now_us(),
                })
                .await;
        }
        let commit = Command {
            command: CommandCode::ConfigCommit as u8,
            token: 0,
            arg: words[PARAM_COUNT],
            arg2: 0,
        };
        let frame = commit.to_frame(0);
        RESTORE
            .send(RxFrame {
                frame,
                timestamp_us: now_us(),
            })
            .await;
    }
    loop {
        Timer::after_millis(200).await;
        let Some((values, crc)) = critical_section::with(|cs| TO_STORE.borrow(cs).take()) else {
            continue;
        };
        let mut words = [0u32; PARAM_COUNT + 1];
        for (w, v) in words.iter_mut().zip(values) {
            *w = v.to_bits();
        }
        words[PARAM_COUNT] = crc;
        // The configuration's node id is the board's from its next start.
        let id = DriveConfig::from_values(&values).node_id as u8;
        if id != node && (1..=15).contains(&id) && node_id(&mut flash).await != Some(id) {
            store_node_id(&mut flash, id).await;
        }
        let _ = store_item(
            &mut flash,
            RANGE,
            &mut NoCache::new(),
            &mut buf,
            &KEY_CONFIG,
            &words,
        )
        .await;
    }
}

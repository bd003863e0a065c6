// SPDX-License-Identifier: MIT
/** Status names: 'ok' or the error (pmz.h's PMZ_OK ... PMZ_ERR_MEMORY). */
export type PmzStatus =
  | 'ok'
  | 'bad_magic'
  | 'bad_version'
  | 'bad_checksum'
  | 'corrupt'
  | 'limit_exceeded'
  | 'truncated'
  | 'out_of_memory';

export declare const STATUS_NAMES: readonly PmzStatus[];

export interface StreamInfo {
  /** The header has been parsed: the counts and bounding box are valid. */
  headerDone: boolean;
  /** The base mesh has been decoded: the mesh is drawable. */
  baseDone: boolean;
  /** The end marker has been seen: every split is available. */
  complete: boolean;
  baseVertices: number;
  baseFaces: number;
  fullVertices: number;
  fullFaces: number;
  totalSplits: number;
  versionMajor: number;
  versionMinor: number;
  flags: number;
  /** 0 = lossless float32. */
  positionBits: number;
  /** The predictor's curvature weights (spec/format.md section 4). */
  curvature: number;
  fineCurvature: number;
  bboxMin: [number, number, number];
  bboxMax: [number, number, number];
  /** Compression level (format 10.0): 0 the default, 1 the speed level. */
  level: number;
}

export interface MeshChanges {
  /** Vertices [vertexBegin, vertexCount) are new or rewritten. */
  vertexBegin: number;
  /** Faces [faceBegin, faceCount) are new or rewritten. */
  faceBegin: number;
  /** Rewritten faces below faceBegin (may repeat, unsorted); a view into the heap. */
  modifiedFaces: Uint32Array;
  /** Everything should be uploaded (e.g. the first base mesh). */
  all: boolean;
  /** Attribute wedges [wedgeBegin, wedgeCount) are new; a face's wedgeIndices() and
   * faceMaterials() entries change exactly when its indices() do. */
  wedgeBegin: number;
}

/** A material as the file states it (OBJ's MTL, glTF's materials): carried, not interpreted. */
export interface PmzMaterial {
  name: string;
  /** Linear RGBA. */
  baseColor: [number, number, number, number];
  /** File name or URI of the base colour texture (relative to the .pmz), '' when none. */
  baseColorTexture: string;
  normalTexture: string;
}

export interface DecoderOptions {
  /** Hard caps checked against the header before allocating; 0 or absent: the defaults. */
  maxVertices?: number;
  maxFaces?: number;
  /** The .wasm bytes, when the file beside the module cannot be fetched or read: the
   * single-threaded module's (pmz_wasm.wasm), so one worker. */
  wasmBinary?: ArrayBuffer | Uint8Array;
  /** Threads that decode a stream's ready nodes at once (streams with a node table, without
   * attributes); default the cores (navigator.hardwareConcurrency, node's
   * os.availableParallelism()), at most 64. More than one loads the threaded module
   * (pmz_wasm_mt.*, workers - 1 web workers) where shared memory is available: node, and
   * cross-origin-isolated pages (COOP and COEP headers; README); elsewhere, or when its files
   * fail to load, the decoder runs on one (Decoder.workers). The mesh, ids, change reports
   * and errors do not depend on it. */
  workers?: number;
}

export declare class Decoder {
  /** The threads decoding: DecoderOptions.workers where the threaded module runs, else 1. */
  readonly workers: number;
  /** Consumes a slice of the stream (any slicing gives the same mesh). */
  feed(bytes: Uint8Array | ArrayBuffer): PmzStatus;
  /** End of input: 'truncated' when the end marker was not seen. */
  finish(): PmzStatus;
  /** The sticky status: refine() can find damage too (a split is decoded when first applied). */
  readonly status: PmzStatus;
  /** One line, '' when ok. */
  readonly error: string;
  /** Applies up to maxSplits available splits (all when absent); returns how many. */
  refine(maxSplits?: number): number;
  /** Undoes up to maxSplits applied splits (all when absent); returns how many. */
  coarsen(maxSplits?: number): number;
  /** Refines for at most budgetMs milliseconds (default 8) and at most maxSplits splits
   * (default: no limit); returns the splits applied. After an error the splits that arrived
   * before the damage are still applied (as refine() does); 0 once none is left. */
  refineFor(budgetMs?: number, maxSplits?: number): number;
  /** The smallest level with at least `faces` faces, clamped to what is available. */
  setFaceTarget(faces: number): void;
  setSplitTarget(splits: number): void;
  readonly faceCount: number;
  readonly vertexCount: number;
  readonly splitsApplied: number;
  readonly splitsAvailable: number;
  readonly bytesConsumed: number;
  readonly complete: boolean;
  info(): StreamInfo;
  /** xyz per vertex: a view into the heap, valid until the next feed or level change. */
  positions(): Float32Array;
  /** Three indices per counter-clockwise face: a view into the heap, valid like positions(). */
  indices(): Uint32Array;
  /** The vertex each vertex was split from (0xFFFFFFFF for base vertices), for geomorphs. */
  splitParents(): Uint32Array;
  /** Attributes (format 8.0): a render vertex is an attribute wedge. 0 without attributes. */
  readonly wedgeCount: number;
  readonly texcoordSetCount: number;
  /** 0 (no colours), 3 (RGB) or 4 (RGBA). */
  readonly colorComponents: number;
  readonly materialCount: number;
  /** Wedge -> position vertex index. Like every attribute view below: zero-copy, valid like
   * positions(), empty without attributes. */
  wedgeVertices(): Uint32Array;
  /** xyz per wedge (positions() of wedgeVertices()). */
  wedgePositions(): Float32Array;
  /** Three wedges per face: the corners of indices(). */
  wedgeIndices(): Uint32Array;
  /** u, v per wedge for texture coordinate set `set` (default 0; v up, as in OBJ). */
  texcoords(set?: number): Float32Array;
  /** Unit xyz per wedge. */
  normals(): Float32Array;
  /** colorComponents floats per wedge. */
  colors(): Float32Array;
  /** Per face an index into materials(). */
  faceMaterials(): Uint32Array;
  /** The material table (copies). */
  materials(): PmzMaterial[];
  /** What changed since the last clearChanges(). */
  changes(): MeshChanges;
  clearChanges(): void;
  /** View-dependent decoding (streams with a node table): moves the mesh towards `view`,
   * whole nodes until about maxSplits splits (all when absent); returns the splits applied or
   * undone. Feed the stream in order up to its node table first (nodeRange(1) not null). */
  updateView(view: PmzView, maxSplits?: number): number;
  /** A face budget for the nodes updateView() applies, from the next call on (0, null or
   * absent: none): the view's nodes largest projected error first, each with its parents, while
   * the mesh's faces stay within it; nodesToFetch() and viewComplete() count those only, and
   * applied nodes it no longer admits are undone. Node 0 is always applied. */
  setViewFaceBudget(faces?: number | null): void;
  /** After updateView(): every node the view needs (within the face budget) is applied. */
  viewComplete(): boolean;
  /** After updateView(): the nodes the view needs whose bytes are missing, parents first. */
  nodesToFetch(): number[];
  /** Node k's bytes in the file; null before the node table arrived or for k out of range. */
  nodeRange(k: number): { offset: number; size: number } | null;
  /** Nodes in the table: 0 before it arrived (or when it holds node 0 alone). */
  readonly nodeCount: number;
  /** Node k's bytes, exactly nodeRange(k)'s; a status as feed() returns. */
  feedNode(k: number, bytes: Uint8Array | ArrayBuffer): PmzStatus;
  /** Nodes whose splits are in the mesh (node 0 included). */
  nodesApplied(): number;
  /** A view for a camera at eye looking at target (y up), as pmz-decode --camera makes. */
  lookAt(eye: ArrayLike<number>, target: ArrayLike<number>, options?: LookAtOptions): PmzView;
  /** Frees the decoder's WebAssembly memory; the decoder is unusable afterwards. */
  dispose(): void;
}

/** A camera for Decoder.updateView(), in the mesh's own coordinates. */
export interface PmzView {
  eye: ArrayLike<number>;
  /** Column-major clip-from-mesh matrix: three.js's camera.projectionMatrix x
   * camera.matrixWorldInverse x mesh.matrixWorld. */
  viewProjection: ArrayLike<number>;
  /** Vertical field of view, radians (default 60 degrees). */
  fovY?: number;
  /** Pixels (default 1080). */
  viewportHeight?: number;
  /** Refine while a node's error spans more pixels than this (default 1). */
  pixelError?: number;
}

export interface LookAtOptions {
  fovY?: number;
  width?: number;
  height?: number;
  near?: number;
  pixelError?: number;
}

export interface RangeSourceOptions {
  /** fetch()'s RequestInit (headers, credentials); Range and signal are set per request. */
  init?: RequestInit;
  /** Requests at once (4). */
  inFlight?: number;
  /** A request fails when no byte arrives for this long (30000 ms). */
  timeoutMs?: number;
  /** The first in-order range (16 KiB); each next one twice as large. */
  firstBytes?: number;
  /** Nodes adjacent in the file are asked for in one request up to this size (1 MiB). */
  mergeBytes?: number;
  /** After bytes were fed. */
  onData?: () => void;
}

/** A .pmz read by byte ranges for view-dependent decoding. */
export declare class RangeSource {
  constructor(decoder: Decoder, url: string | URL, options?: RangeSourceOptions);
  readonly decoder: Decoder;
  /** Response bytes received. */
  readonly bytes: number;
  /** The file's size once a response said it (0 before). */
  readonly totalBytes: number;
  readonly requests: number;
  readonly nodesFetched: number;
  /** Reading the rest in order (no node table, attributes, or a server that ignores Range). */
  readonly inOrder: boolean;
  /** The first failed request or bad response, one line ('' while none). */
  readonly error: string;
  /** Nothing in flight, queued or being read in order. */
  readonly idle: boolean;
  /** Reads in order up to the node table (or the whole stream without one); rejects on a
   * failed request or a bad response. */
  open(): Promise<void>;
  /** Queues the nodes to fetch (Decoder.nodesToFetch()), most wanted first. */
  want(ids: readonly number[]): void;
  /** Resolves once something arrived or failed. */
  changed(): Promise<void>;
  /** Stops every request. */
  close(): void;
}

export interface LoadViewResult {
  status: PmzStatus;
  complete: boolean;
  bytes: number;
  totalBytes: number;
  requests: number;
  nodesFetched: number;
  inOrder: boolean;
}

/** Decodes what `view` needs from url, fetched by ranges; rejects on a failed request or a bad
 * response (one line). */
export declare function loadView(
  decoder: Decoder,
  url: string | URL,
  view: PmzView,
  options?: RangeSourceOptions & { maxSplits?: number; maxFaces?: number },
): Promise<LoadViewResult>;

export declare function createDecoder(options?: DecoderOptions): Promise<Decoder>;

/** Feeds a stream into the decoder as it arrives, then finish(); resolves to the status. */
export declare function feedStream(
  decoder: Decoder,
  stream: ReadableStream<Uint8Array>,
  onData?: (bytesSoFar: number) => void,
): Promise<PmzStatus>;

/** fetch(url) streamed into the decoder; totalBytes from Content-Length (0 when unknown). */
export declare function fetchInto(
  decoder: Decoder,
  url: string | URL,
  onData?: (bytesSoFar: number, totalBytes: number) => void,
  init?: RequestInit,
): Promise<PmzStatus>;
